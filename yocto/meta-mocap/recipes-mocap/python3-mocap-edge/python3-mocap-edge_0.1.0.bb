# nooelint: oelint.var.mandatoryvar.SRC_URI,oelint.var.mandatoryvar.HOMEPAGE,oelint.var.suggestedvar.BUGTRACKER,oelint.var.bbclassextend - this repository's own source (mocap-source.inc); it has no public home page or tracker yet; it runs on the boxes only
SUMMARY = "The mocap system's edge boxes: camera boxes and the IMU hub"
DESCRIPTION = "The camera box (frames from libcamera, keypoints by an ONNX model, frame-trigger \
               timestamps from a GPIO line) and the IMU hub (sensor nodes on CAN, IMUs on I2C) \
               publishing to the host over ZeroMQ: the Python package mocap_edge with the part \
               of the host package it imports, as scripts/edge_dist.py assembles them."
LICENSE = "Apache-2.0"
LIC_FILES_CHKSUM = "file://LICENSE;md5=3b83ef96387f14655fc854ddc3c6bd57"

DEPENDS += "protobuf-native"

require recipes-mocap/mocap-source.inc

inherit python_setuptools_build_meta

# The distribution is assembled from the checkout into the build folder (the checkout is
# never written): the edge's modules, the generated wire modules, the data files.
PEP517_SOURCE_PATH = "${B}/dist"

do_configure:prepend() {
    ${PYTHON} ${S}/scripts/edge_dist.py --protoc ${STAGING_BINDIR_NATIVE}/protoc ${B}/dist
}

# What the code imports (the layer's tests derive this list from the code and fail on a
# module no package provides); python3-modules is the whole standard library.
RDEPENDS:${PN} += "\
    mocap-edge-libs \
    mocap-models-blazepose \
    python3-can \
    python3-cantools \
    python3-gpiod \
    python3-modules \
    python3-numpy \
    python3-onnxruntime \
    python3-opencv \
    python3-protobuf \
    python3-pyserial \
    python3-pyzmq \
    python3-smbus2 \
"
