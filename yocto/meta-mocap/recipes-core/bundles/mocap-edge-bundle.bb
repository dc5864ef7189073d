# nooelint: oelint.file.underscores,oelint.var.mandatoryvar.SRC_URI,oelint.var.mandatoryvar.HOMEPAGE,oelint.var.suggestedvar.BUGTRACKER,oelint.var.suggestedvar.CVE_PRODUCT,oelint.var.bbclassextend - a bundle is named after its image and versioned by the distribution (RAUC_BUNDLE_VERSION); its only source is the image; the project has no public home page or tracker yet; no CVE product; built for the target only
SUMMARY = "RAUC update bundle of the mocap edge image"
DESCRIPTION = "The mocap-edge-image root file system as a signed RAUC bundle: `rauc install` on \
               a box writes it to the slot not running and boots it, falling back to the other \
               slot when it does not come up (yocto/README.md, Updating boxes)."
SECTION = "mocap"
LICENSE = "MIT"

inherit bundle

RAUC_BUNDLE_COMPATIBLE = "${MACHINE}"
RAUC_BUNDLE_VERSION = "${DISTRO_VERSION}"
RAUC_BUNDLE_DESCRIPTION = "mocap edge image"
RAUC_BUNDLE_FORMAT = "verity"

RAUC_BUNDLE_SLOTS = "rootfs"
# nooelint: oelint.vars.mispell.unknown - meta-rauc's bundle class names this variable after the slot
RAUC_SLOT_rootfs = "mocap-edge-image"
# nooelint: oelint.vars.mispell.unknown - the same variable's flag
RAUC_SLOT_rootfs[fstype] = "ext4"

# The signing key and certificate are the builder's (RAUC_KEY_FILE, RAUC_CERT_FILE in
# local.conf or a kas file); the boxes trust the matching CA (rauc-conf's keyring).
