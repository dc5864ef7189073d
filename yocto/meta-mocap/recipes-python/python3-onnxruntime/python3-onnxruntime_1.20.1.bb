# nooelint: oelint.var.bbclassextend - a prebuilt aarch64 wheel: there is no native variant
SUMMARY = "ONNX Runtime: the camera box's keypoint inference"
DESCRIPTION = "Microsoft's ONNX Runtime from its prebuilt aarch64 wheel on PyPI (the version the \
               project's tests run). No public layer ships a current ONNX Runtime, and a source \
               build fetches its third-party sources at configure time (CMake FetchContent), \
               which BitBake's compile tasks may not do; the wheel is the build its maintainers \
               test on aarch64 Linux."
HOMEPAGE = "https://onnxruntime.ai"
BUGTRACKER = "https://github.com/microsoft/onnxruntime/issues"
SECTION = "devel/python"
LICENSE = "MIT"
LIC_FILES_CHKSUM = "file://onnxruntime/LICENSE;md5=0f7e3b1308cb5c00b372a6e78835732d"
CVE_PRODUCT = "microsoft:onnxruntime"

WHEEL_TAG = "cp312-cp312-manylinux_2_27_aarch64.manylinux_2_28_aarch64"
SRC_URI = "https://files.pythonhosted.org/packages/c5/9d/a42a84e10f1744dd27c6f2f9280cc3fb98f869dd19b7cd042e391ee2ab61/onnxruntime-${PV}-${WHEEL_TAG}.whl;downloadfilename=onnxruntime-${PV}-${WHEEL_TAG}.zip;subdir=${BP}"
SRC_URI[sha256sum] = "f1f56e898815963d6dc4ee1c35fc6c36506466eff6d16f3cb9848cea4e8c8172"

# The wheel is built for aarch64 and CPython 3.12 (scarthgap's Python).
COMPATIBLE_HOST = "aarch64.*-linux"

inherit python3-dir

do_configure[noexec] = "1"
do_compile[noexec] = "1"

do_install() {
    install -d ${D}${PYTHON_SITEPACKAGES_DIR}
    cp -r --no-preserve=ownership ${S}/onnxruntime ${S}/onnxruntime-${PV}.dist-info ${D}${PYTHON_SITEPACKAGES_DIR}/
}

FILES:${PN} += "${PYTHON_SITEPACKAGES_DIR}"
RDEPENDS:${PN} += "\
    libstdc++ \
    python3-coloredlogs \
    python3-flatbuffers \
    python3-numpy \
    python3-packaging \
    python3-protobuf \
    python3-sympy \
"
# nooelint: oelint.vars.insaneskip - prebuilt by its maintainers: already stripped, linked with their flags
INSANE_SKIP:${PN} += "already-stripped ldflags"
