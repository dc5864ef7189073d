# nooelint: oelint.var.suggestedvar.BUGTRACKER,oelint.var.suggestedvar.CVE_PRODUCT - the project has no public tracker yet; an image is no CVE product
SUMMARY = "A mocap edge box: camera box, IMU hub, or both"
DESCRIPTION = "One image for every box: the services that run are chosen by the box's settings \
               on its data partition (/data/mocap/camera@N.conf: a camera box for camera N; \
               /data/mocap/hub.toml: the IMU hub), so a spare box takes any role. Read-only root \
               file system, A/B updated by RAUC."
SECTION = "mocap"
LICENSE = "MIT"

inherit core-image

IMAGE_FEATURES += "read-only-rootfs ssh-server-openssh"

# The kernel is in each root file system slot: the A/B boot script loads the slot's own.
IMAGE_INSTALL += "\
    can-utils \
    iproute2 \
    kernel-image \
    kernel-modules \
    libcamera \
    linuxptp \
    mocap-box-services-camera \
    mocap-box-services-hub \
    python3-mocap-edge \
    rauc \
"

# The builder's SSH public keys (a file of authorized_keys lines), given root on every box: how
# boxes are configured and updated over the network (yocto/README.md). Unset: no SSH login.
MOCAP_SSH_AUTHORIZED_KEYS ??= ""
ROOTFS_POSTPROCESS_COMMAND += "mocap_authorized_keys"
mocap_authorized_keys[doc] = "Installs MOCAP_SSH_AUTHORIZED_KEYS as root's authorized_keys"

mocap_authorized_keys() {
    if [ -n "${MOCAP_SSH_AUTHORIZED_KEYS}" ]; then
        install -d -m 0700 ${IMAGE_ROOTFS}${ROOT_HOME}/.ssh
        install -m 0600 ${MOCAP_SSH_AUTHORIZED_KEYS} ${IMAGE_ROOTFS}${ROOT_HOME}/.ssh/authorized_keys
    fi
}
