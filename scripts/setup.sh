#!/usr/bin/env bash
# Installs everything the project needs on a fresh Debian 12 machine (run as root).
# Idempotent: re-running only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

DEBIAN_PACKAGES=(
  build-essential cmake ninja-build pkg-config clang-format
  libceres-dev libeigen3-dev nlohmann-json3-dev pybind11-dev libgtest-dev
  protobuf-compiler libprotobuf-dev libzmq3-dev cppzmq-dev
  python3 python3-dev python3-venv
  gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm libcmocka-dev
  clang libclang-rt-14-dev
  libcamera-dev
)

missing=()
for p in "${DEBIAN_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The Python environment uses Debian's interpreter, whatever else is on PATH.
PY=/usr/bin/python3
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -r requirements.txt
.venv/bin/python -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
.venv/bin/python -m mocap.io.demo_data  # the demo's motion (PyPI pose2sim) into .cache/
echo "setup: done"
