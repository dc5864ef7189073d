# nooelint: oelint.var.mandatoryvar.SRC_URI,oelint.var.mandatoryvar.HOMEPAGE,oelint.var.suggestedvar.BUGTRACKER,oelint.var.bbclassextend - this repository's own source (mocap-source.inc); it has no public home page or tracker yet; it runs on the boxes only
SUMMARY = "systemd services of the mocap edge boxes"
DESCRIPTION = "The camera box (mocap-camera@.service, one instance per camera of the board), \
               the IMU hub (mocap-imu-hub.service, can0 by systemd-networkd), ptp4l's settings \
               (client, or the studio's grandmaster) and the wait for the PTP clock that both \
               start after, the mocap user and its devices, and example \
               settings for /data/mocap (edge/systemd)."
LICENSE = "Apache-2.0"
LIC_FILES_CHKSUM = "file://LICENSE;md5=3b83ef96387f14655fc854ddc3c6bd57"

require recipes-mocap/mocap-source.inc

inherit allarch systemd useradd

PACKAGES = "${PN}-clock ${PN}-camera ${PN}-hub"

USERADD_PACKAGES = "${PN}-clock"
GROUPADD_PARAM:${PN}-clock = "-r gpio; -r i2c"
USERADD_PARAM:${PN}-clock = "-r -d /data/mocap -s /bin/false -G video,gpio,i2c -U mocap"

SYSTEMD_PACKAGES = "${PN}-clock ${PN}-camera ${PN}-hub"
SYSTEMD_SERVICE:${PN}-clock = "mocap-clock-sync.service"
SYSTEMD_SERVICE:${PN}-camera = "mocap-camera@.service"
SYSTEMD_SERVICE:${PN}-hub = "mocap-imu-hub.service"

do_configure[noexec] = "1"
do_compile[noexec] = "1"

do_install() {
    install -d ${D}${systemd_system_unitdir} ${D}${bindir} ${D}${sysconfdir}/systemd/network \
        ${D}${sysconfdir}/udev/rules.d ${D}${nonarch_libdir}/tmpfiles.d \
        ${D}${datadir}/mocap-edge/examples
    install -m 0644 ${S}/edge/systemd/mocap-camera@.service ${S}/edge/systemd/mocap-imu-hub.service \
        ${S}/edge/systemd/mocap-clock-sync.service ${D}${systemd_system_unitdir}/
    install -m 0755 ${S}/edge/systemd/mocap-wait-clock ${D}${bindir}/
    install -m 0644 ${S}/edge/systemd/80-mocap-can0.network ${D}${sysconfdir}/systemd/network/
    install -m 0644 ${S}/edge/systemd/99-mocap-devices.rules ${D}${sysconfdir}/udev/rules.d/
    install -m 0644 ${S}/edge/systemd/mocap-edge.tmpfiles ${D}${nonarch_libdir}/tmpfiles.d/mocap-edge.conf
    install -m 0644 ${S}/edge/systemd/examples/camera@0.conf ${S}/edge/systemd/examples/imu-hub.conf \
        ${S}/edge/systemd/examples/hub.toml ${S}/edge/systemd/examples/clock.conf \
        ${D}${datadir}/mocap-edge/examples/
    install -d ${D}${sysconfdir}/linuxptp ${D}${systemd_system_unitdir}/ptp4l@.service.d
    install -m 0644 ${S}/edge/systemd/ptp4l-box.conf ${S}/edge/systemd/ptp4l-grandmaster.conf \
        ${D}${sysconfdir}/linuxptp/
    install -m 0644 ${S}/edge/systemd/ptp4l@.service.d/mocap.conf ${D}${systemd_system_unitdir}/ptp4l@.service.d/
    # Camera 1 as well as camera 0 (the unit's default instance): a board with two camera
    # ports runs both; either starts only once its settings are on /data.
    install -d ${D}${sysconfdir}/systemd/system/multi-user.target.wants
    ln -sf ${systemd_system_unitdir}/mocap-camera@.service \
        ${D}${sysconfdir}/systemd/system/multi-user.target.wants/mocap-camera@1.service
}

FILES:${PN}-clock += "\
    ${bindir}/mocap-wait-clock \
    ${sysconfdir}/linuxptp \
    ${systemd_system_unitdir}/ptp4l@.service.d \
    ${datadir}/mocap-edge/examples \
    ${nonarch_libdir}/tmpfiles.d \
    ${sysconfdir}/udev/rules.d \
    ${systemd_system_unitdir}/mocap-clock-sync.service \
"
FILES:${PN}-camera += "${sysconfdir}/systemd/system ${systemd_system_unitdir}/mocap-camera@.service"
FILES:${PN}-hub += "${sysconfdir}/systemd/network ${systemd_system_unitdir}/mocap-imu-hub.service"

RDEPENDS:${PN}-clock += "linuxptp"
RDEPENDS:${PN}-camera += "${PN}-clock python3-mocap-edge"
RDEPENDS:${PN}-hub += "${PN}-clock python3-mocap-edge"
