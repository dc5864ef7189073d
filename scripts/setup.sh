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
# The device test VM (tests/vm): QEMU, the tools the in-VM tests run, the kernel headers and
# source its two extra modules are built from. Its kernel is pinned in tests/vm/KERNEL while
# Debian's archive has it; once the archive has moved to a newer kernel ABI (the old headers
# package leaves it), the one linux-image-amd64 depends on, with a warning. The choice goes to
# .cache/vm-kernel, which tests/vm/build.py reads.
VM_KERNEL=$(cat tests/vm/KERNEL)
if ! apt-cache show "linux-headers-$VM_KERNEL" >/dev/null 2>&1; then
  apt-get update -qq
  if ! apt-cache show "linux-headers-$VM_KERNEL" >/dev/null 2>&1; then
    pinned=$VM_KERNEL
    VM_KERNEL=$(apt-cache depends linux-image-amd64 | sed -n 's/^ *Depends: linux-image-//p' | head -n 1)
    echo "setup: warning: linux-headers-$pinned is no longer in Debian's archive; the device test VM" \
         "uses $VM_KERNEL (update tests/vm/KERNEL)"
  fi
fi
mkdir -p .cache && echo "$VM_KERNEL" > .cache/vm-kernel
DEBIAN_PACKAGES+=(
  qemu-system-x86 busybox-static udev can-utils i2c-tools libcamera-tools libcamera-ipa
  "linux-headers-$VM_KERNEL" linux-source-6.1
)
# The monitor page's test (tests/test_monitor_page.py) drives Debian's Chromium headless. Node.js and
# npm install the page's three.js (below): from Debian unless the machine has them already.
DEBIAN_PACKAGES+=(chromium)
# The glTF export's test imports it with Blender's own importer, which needs numpy.
DEBIAN_PACKAGES+=(blender python3-numpy)
command -v npm >/dev/null 2>&1 || DEBIAN_PACKAGES+=(nodejs npm)
# The Yocto layer's tests (yocto/tests): systemd-analyze checks the boxes' units in a root that
# has linuxptp's ptp4l@.service, which they start after.
DEBIAN_PACKAGES+=(systemd linuxptp)

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

# The VM's kernel image: extracted into .cache (never installed on this machine).
vm_kernel=".cache/vm-$VM_KERNEL/kernel"
if [ ! -f "$vm_kernel/boot/vmlinuz-$VM_KERNEL" ]; then
  echo "setup: extracting linux-image-$VM_KERNEL into $vm_kernel"
  download=$(mktemp -d)
  chmod 1777 "$download"  # apt's download user writes there
  (cd "$download" && apt-get download -q "linux-image-$VM_KERNEL")
  rm -rf "$vm_kernel" && mkdir -p "$vm_kernel"
  dpkg -x "$download"/linux-image-*.deb "$vm_kernel"
  rm -rf "$download"
fi

# The Python environment uses Debian's interpreter, whatever else is on PATH.
PY=/usr/bin/python3
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -r requirements.txt
.venv/bin/python -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
# The npm packages, each folder's pinned by its package-lock.json: the monitor page's three.js, and
# the readers the tests run with node (Khronos' glTF validator). Installed again when a lock changes.
for folder in host/python/mocap/monitor/web tests/node; do
  if [ ! -f "$folder/node_modules/.package-lock.json" ] || [ "$folder/package-lock.json" -nt "$folder/node_modules/.package-lock.json" ]; then
    echo "setup: installing the npm packages of $folder (npm ci)"
    npm ci --prefix "$folder" --no-audit --no-fund --loglevel=error
  fi
done
.venv/bin/python -m mocap.io.demo_data  # the demo's motion (PyPI pose2sim) into .cache/
echo "setup: done"
