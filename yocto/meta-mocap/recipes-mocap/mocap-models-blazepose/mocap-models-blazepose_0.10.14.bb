# nooelint: oelint.var.mandatoryvar.SRC_URI,oelint.var.mandatoryvar.HOMEPAGE,oelint.var.suggestedvar.BUGTRACKER,oelint.var.bbclassextend - the models are in this repository (mocap-source.inc); it has no public home page or tracker yet; data for the boxes only
SUMMARY = "BlazePose keypoint models for the mocap camera box"
DESCRIPTION = "MediaPipe's (0.10.14) BlazePose person detector and full-body landmark model, \
               converted to ONNX (edge/models/blazepose/README.md says how, and checks them)."
LICENSE = "Apache-2.0"
LIC_FILES_CHKSUM = "file://edge/models/blazepose/LICENSE;md5=87a30e5cfa12d1ab9ada4fb6f3feed4b"

require recipes-mocap/mocap-source.inc

inherit allarch

do_configure[noexec] = "1"
do_compile[noexec] = "1"

do_install() {
    install -d ${D}${datadir}/mocap-edge/models/blazepose
    install -m 0644 ${S}/edge/models/blazepose/pose_detection.onnx \
        ${S}/edge/models/blazepose/pose_landmark_full.onnx \
        ${S}/edge/models/blazepose/LICENSE \
        ${D}${datadir}/mocap-edge/models/blazepose/
}

FILES:${PN} += "${datadir}/mocap-edge/models"
