# nooelint: oelint.var.mandatoryvar.SRC_URI,oelint.var.mandatoryvar.HOMEPAGE,oelint.var.suggestedvar.BUGTRACKER,oelint.var.bbclassextend - this repository's own source (mocap-source.inc); it has no public home page or tracker yet; it runs on the boxes only
SUMMARY = "The mocap edge boxes' native parts"
DESCRIPTION = "The sensor node's orientation filter as a shared library (the IMU hub's own I2C \
               IMUs run the node's algorithm) and the camera box's libcamera capture (a Python \
               extension), built by the repository's CMake with MOCAP_EDGE_BOX."
LICENSE = "Apache-2.0"
LIC_FILES_CHKSUM = "file://LICENSE;md5=3b83ef96387f14655fc854ddc3c6bd57"

DEPENDS += "libcamera python3-pybind11"

require recipes-mocap/mocap-source.inc

inherit cmake pkgconfig python3native python3targetconfig

EXTRA_OECMAKE += "\
    -DMOCAP_EDGE_BOX=ON \
    -DMOCAP_PYTHON_SITE=${@os.path.relpath(d.getVar('PYTHON_SITEPACKAGES_DIR'), d.getVar('prefix'))} \
"

# Both are modules of python3-mocap-edge's folders, loaded by path (not libraries to link).
FILES:${PN} += "${PYTHON_SITEPACKAGES_DIR}/mocap_edge"
