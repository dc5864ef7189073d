"""The device test VM's build products, under .cache/vm-<kernel>/ (rebuilt only when missing
or when their key changes: the kernel, the Debian packages they are built from, this file
and the init script):

- kernel/: Debian's linux-image package of tests/vm/KERNEL, extracted by scripts/setup.sh;
- modules/: vimc.ko and gpio-sim.ko, which Debian's configuration leaves out, built out of
  tree from linux-source-6.1 against the matching linux-headers (gpio-sim with the kernel's
  irq_sim.c bundled in: Debian builds no IRQ_SIM, and the module calls generic_handle_irq
  where the built-in code calls handle_simple_irq(irq_to_desc()), which is not exported);
- initramfs.cpio.gz: busybox, the 9p/virtio modules that reach the host's files, the init
  script, and the ordered list of device modules init loads from the host (with their
  parameters: i2c-stub answers at the hub-local IMU's address).

`python tests/vm/build.py` builds what is missing and prints the paths.
"""

from __future__ import annotations

import gzip
import hashlib
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
# the kernel scripts/setup.sh chose (tests/vm/KERNEL unless Debian's archive has moved on)
KERNEL = next(p.read_text().strip() for p in (ROOT / ".cache" / "vm-kernel", HERE / "KERNEL") if p.is_file())
CACHE = ROOT / ".cache" / f"vm-{KERNEL}"
KERNEL_ROOT = CACHE / "kernel"
VMLINUZ = KERNEL_ROOT / "boot" / f"vmlinuz-{KERNEL}"
MODULES = CACHE / "modules"
INITRAMFS = CACHE / "initramfs.cpio.gz"
KEY_FILE = CACHE / "key"
HEADERS = Path(f"/usr/src/linux-headers-{KERNEL}")
SOURCE_TAR = Path("/usr/src/linux-source-6.1.tar.xz")
BUSYBOX = Path("/bin/busybox")
PACKAGES = (f"linux-headers-{KERNEL}", "linux-source-6.1", "busybox-static")
IMU_ADDRESS = 0x68  # the hub-local ICM-42688-P with AD0 low (mocap_edge.hub.i2c.regs)

BOOT_MODULES = ("virtio_pci", "9pnet_virtio", "9p")  # reaching the host's files
DEVICE_MODULES = (("vcan", ""), ("can_raw", ""), ("i2c_stub", f"chip_addr=0x{IMU_ADDRESS:02x}"),
                  ("i2c_dev", ""), ("configfs", ""), ("gpio_sim", ""), ("vimc", ""))
VIMC_FILES = ("core", "common", "streamer", "capture", "debayer", "scaler", "sensor", "lens")
KBUILD = f"""obj-m += vimc.o gpio-sim.o
vimc-y := {' '.join(f'vimc-{name}.o' for name in VIMC_FILES)}
gpio-sim-y := gpio-sim-core.o irq_sim.o
"""


class BuildError(RuntimeError):
    """Something the VM needs is not installed (run `make setup`) or did not build."""


def key() -> str:
    """What the products depend on: a change rebuilds them."""
    versions = []
    for package in PACKAGES:
        found = subprocess.run(["dpkg-query", "-W", "-f=${Version}", package], capture_output=True, text=True)
        if found.returncode != 0:
            raise BuildError(f"the Debian package {package} is not installed: run `make setup`")
        versions.append(f"{package}={found.stdout}")
    text = "\n".join([KERNEL, *versions, Path(__file__).read_text(), (HERE / "init").read_text()])
    return hashlib.sha256(text.encode()).hexdigest()


def ensure() -> None:
    """The kernel, modules and initramfs, built when missing or stale."""
    if not VMLINUZ.is_file():
        raise BuildError(f"no {VMLINUZ} (the linux-image-{KERNEL} package, extracted): run `make setup`")
    wanted = key()
    if KEY_FILE.is_file() and KEY_FILE.read_text() == wanted and INITRAMFS.is_file() and \
            all((MODULES / f"{m}.ko").is_file() for m in ("vimc", "gpio-sim")):
        return
    build_modules()
    build_initramfs()
    KEY_FILE.write_text(wanted)


def build_modules() -> None:
    if not (HEADERS / "Makefile").is_file() or not SOURCE_TAR.is_file():
        raise BuildError(f"{HEADERS} or {SOURCE_TAR} missing: run `make setup`")
    with tempfile.TemporaryDirectory(prefix="vm-modules-") as tmp:
        work, src = Path(tmp), Path(tmp) / "linux-source-6.1"
        members = ["drivers/media/test-drivers/vimc", "drivers/gpio/gpio-sim.c", "drivers/gpio/gpiolib.h",
                   "kernel/irq/irq_sim.c"]
        _run(["tar", "-xJf", str(SOURCE_TAR), "-C", tmp, *(f"linux-source-6.1/{m}" for m in members)])
        build = work / "build"
        build.mkdir()
        for name in VIMC_FILES:
            for suffix in (".c", ".h"):
                source = src / "drivers/media/test-drivers/vimc" / f"vimc-{name}{suffix}"
                if source.is_file():
                    shutil.copy(source, build)
        shutil.copy(src / "drivers/gpio/gpiolib.h", build)
        shutil.copy(src / "drivers/gpio/gpio-sim.c", build / "gpio-sim-core.c")
        irq_sim = (src / "kernel/irq/irq_sim.c").read_text()
        patched = irq_sim.replace("handle_simple_irq(irq_to_desc(irqnum))", "generic_handle_irq(irqnum)")
        if patched == irq_sim:
            raise BuildError("irq_sim.c changed: its handle_simple_irq(irq_to_desc(irqnum)) call is not there")
        (build / "irq_sim.c").write_text(patched)
        (build / "Kbuild").write_text(KBUILD)
        _run(["make", "-s", "-C", str(HEADERS), f"M={build}", "modules"])
        MODULES.mkdir(parents=True, exist_ok=True)
        for module in ("vimc.ko", "gpio-sim.ko"):
            shutil.copy(build / module, MODULES / module)


def _run(command: list[str]) -> None:
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise BuildError(f"{' '.join(command[:4])} ... failed:\n{done.stdout[-3000:]}{done.stderr[-3000:]}")


def module_index() -> dict[str, Path]:
    """Module name (underscores) -> its .ko: Debian's, and the two built here."""
    index = {p.stem.replace("-", "_"): p for p in (KERNEL_ROOT / "lib/modules" / KERNEL / "kernel").rglob("*.ko")}
    index.update({p.stem.replace("-", "_"): p for p in MODULES.glob("*.ko")})
    return index


def load_order(names: list[str], index: dict[str, Path], loaded: set[str] | None = None) -> list[str]:
    """`names` and the modules they depend on (each module's modinfo `depends=`), dependencies
    first, none twice, none in `loaded`."""
    order: list[str] = []
    seen = set(loaded or ())

    def visit(name: str) -> None:
        if name in seen:
            return
        seen.add(name)
        if name not in index:
            raise BuildError(f"kernel module {name} not found in {KERNEL_ROOT} or {MODULES}")
        found = re.search(rb"\0depends=([^\0]*)\0", b"\0" + index[name].read_bytes())
        for dependency in filter(None, (found.group(1).decode().split(",") if found else [])):
            visit(dependency.replace("-", "_"))
        order.append(name)

    for name in names:
        visit(name)
    return order


def build_initramfs() -> None:
    """busybox, the boot modules, /init, and /device-modules: the device modules' paths on the
    host (from the host's root) and parameters, one a line, in load order."""
    index = module_index()
    boot = load_order(list(BOOT_MODULES), index)
    devices = load_order([name for name, _ in DEVICE_MODULES], index, loaded=set(boot))
    params = dict(DEVICE_MODULES)
    archive = Cpio()
    for folder in ("bin", "dev", "proc", "sys", "host", "modules"):
        archive.add(folder, b"", 0o040755)
    archive.add("dev/console", b"", 0o020600, device=(5, 1))
    archive.add("bin/busybox", BUSYBOX.read_bytes(), 0o100755)
    archive.add("init", (HERE / "init").read_bytes(), 0o100755)
    for name in boot:
        archive.add(f"modules/{name}.ko", index[name].read_bytes(), 0o100644)
    archive.add("boot-modules", "".join(f"/modules/{name}.ko\n" for name in boot).encode(), 0o100644)
    lines = "".join(f"{index[name]} {params.get(name, '')}".rstrip() + "\n" for name in devices)
    archive.add("device-modules", lines.encode(), 0o100644)
    INITRAMFS.parent.mkdir(parents=True, exist_ok=True)
    INITRAMFS.write_bytes(gzip.compress(archive.finish(), compresslevel=6))


class Cpio:
    """A cpio archive in the kernel's initramfs format (newc)."""

    def __init__(self) -> None:
        self.data = bytearray()
        self.inode = 1

    def add(self, name: str, content: bytes, mode: int, device: tuple[int, int] = (0, 0)) -> None:
        fields = [self.inode, mode, 0, 0, 1, 0, len(content), 0, 0, device[0], device[1], len(name) + 1, 0]
        self.inode += 1
        self.data += b"070701" + "".join(f"{v:08x}" for v in fields).encode() + name.encode() + b"\0"
        self.data += b"\0" * (-len(self.data) % 4) + content
        self.data += b"\0" * (-len(self.data) % 4)

    def finish(self) -> bytes:
        self.add("TRAILER!!!", b"", 0)
        return bytes(self.data)


if __name__ == "__main__":
    try:
        ensure()
    except BuildError as e:
        sys.exit(f"vm: {e}")
    print(f"vm: {VMLINUZ}\nvm: {INITRAMFS}\nvm: {MODULES}/vimc.ko gpio-sim.ko")
