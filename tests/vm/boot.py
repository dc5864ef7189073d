"""Boots the device test VM once: Debian's kernel (tests/vm/KERNEL) in qemu-system-x86_64 with
TCG (KVM does not work on the development machines), the host's root shared read-only over
virtio-9p (the checkout, its .venv and the host's tools run unchanged inside), a results
folder shared writable. The VM runs the in-VM tests (tests/vm/guest) and powers off; QEMU is
killed when it outlives `timeout_s`, when the caller is interrupted, and when the process that started it
ends however it ends (PR_SET_PDEATHSIG): it never stays behind.

`python tests/vm/boot.py [RESULTS_DIR] [--timeout S]` boots it from the command line (the in-VM pytest's
log is printed; exit status that of the in-VM pytest).
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mocap import processes

if __package__:  # imported: tests/test_devices_vm.py's `from vm import boot`
    from . import build
else:  # run as a script: its folder is on sys.path
    import build

QEMU = "qemu-system-x86_64"
TIMEOUT_S = 280.0  # the whole VM part stays under 5 minutes on 2 cores


@dataclasses.dataclass
class VmRun:
    results: Path  # junit.xml, status, pytest.log, setup.log, console.log, qemu.log
    status: int | None  # the in-VM pytest's exit status; None: it never wrote one
    wall_s: float
    timed_out: bool

    def text(self, name: str) -> str:
        path = self.results / name
        return path.read_text(errors="replace") if path.is_file() else ""


def qemu_missing() -> str | None:
    """Why QEMU cannot run here at all, or None."""
    if shutil.which(QEMU) is None:
        return f"{QEMU} is not installed (run `make setup`)"
    probe = subprocess.run([QEMU, "-accel", "help"], capture_output=True, text=True)
    if probe.returncode != 0 or "tcg" not in probe.stdout:
        return f"{QEMU} has no TCG accelerator: {probe.stdout.strip()} {probe.stderr.strip()}"
    return None


def command(results: Path) -> list[str]:
    append = f"console=ttyS0 quiet panic=-1 MOCAP_REPO={build.ROOT} MOCAP_RESULTS={results}"
    share = "local,security_model=none,multidevs=remap"
    return [QEMU, "-accel", "tcg", "-cpu", "max", "-m", "1536", "-smp", "2", "-display", "none", "-monitor", "none",
            "-serial", f"file:{results / 'console.log'}", "-no-reboot", "-nic", "none",
            "-kernel", str(build.VMLINUZ), "-initrd", str(build.INITRAMFS), "-append", append,
            "-virtfs", f"{share},path=/,mount_tag=hostroot,readonly=on",
            "-virtfs", f"{share},path={build.ROOT},mount_tag=repo,readonly=on",
            "-virtfs", f"{share},path={results},mount_tag=results"]


def run(results: Path, timeout_s: float = TIMEOUT_S) -> VmRun:
    """Builds what is missing (tests/vm/build.py), boots, waits for the VM to power off."""
    build.ensure()
    results.mkdir(parents=True, exist_ok=True)
    for stale in ("junit.xml", "status", "pytest.log", "setup.log", "console.log", "qemu.log"):
        (results / stale).unlink(missing_ok=True)
    start = time.monotonic()
    with open(results / "qemu.log", "wb") as log:
        qemu = subprocess.Popen(command(results), stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                preexec_fn=processes.die_with_parent())
    timed_out = False
    try:
        qemu.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        timed_out = True
    finally:  # a timeout, or the caller interrupted (KeyboardInterrupt): no QEMU left behind
        if qemu.poll() is None:
            qemu.kill()
        qemu.wait()
    status = (results / "status").read_text().strip() if (results / "status").is_file() else ""
    return VmRun(results, int(status) if status.lstrip("-").isdigit() else None, time.monotonic() - start, timed_out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", nargs="?", help="folder for the results (default: a new temporary one)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S, help="kill QEMU after this many seconds")
    a = parser.parse_args()
    results = Path(a.results or tempfile.mkdtemp(prefix="vm-results-")).resolve()
    done = run(results, a.timeout)
    print(done.text("pytest.log") or done.text("console.log"))
    print(f"vm: {'timed out after' if done.timed_out else 'powered off after'} {done.wall_s:.1f} s; "
          f"in-VM pytest status {done.status}; results in {results}")
    return 1 if done.status is None else done.status


if __name__ == "__main__":
    sys.exit(main())
