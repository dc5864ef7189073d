"""The edge's device paths against real Linux kernel drivers: a Debian kernel booted in QEMU
(tests/vm) with vcan (SocketCAN), i2c-stub (an SMBus chip with registers), gpio-sim (a GPIO
chip whose lines are driven through configfs/sysfs) and vimc (a media-controller camera), the
in-VM tests in tests/vm/guest run through the project's own code. The VM boots once for this
module; each in-VM test is one test here, failing with the in-VM failure's text. Skipped only
where QEMU cannot run at all. docs/devices.md says what the stand-ins model and what not."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import pytest
from vm import boot

GUEST = Path(__file__).resolve().parent / "vm" / "guest"


def guest_tests() -> list[str]:
    """file::test of every in-VM test (tests/vm/guest/vm_*.py), in file order."""
    return [f"{path.name}::{name}" for path in sorted(GUEST.glob("vm_*.py"))
            for name in re.findall(r"^def (test_\w+)", path.read_text(), re.MULTILINE)]


@pytest.fixture(scope="module")
def vm(tmp_path_factory) -> boot.VmRun:
    reason = boot.qemu_missing()
    if reason:
        pytest.skip(f"the device test VM cannot run here: {reason}")
    return boot.run(tmp_path_factory.mktemp("vm-results"))


def outcomes(run: boot.VmRun) -> dict[str, tuple[str, str]]:
    """file::test -> (passed / failed / skipped, text) from the in-VM junit XML (an in-VM test
    never skips: the VM has every device it needs)."""
    found = {}
    for case in ElementTree.fromstring(run.text("junit.xml")).iter("testcase"):
        key = f"{case.get('classname').rpartition('.')[2]}.py::{case.get('name')}"
        problem = next((e for e in case if e.tag in ("failure", "error", "skipped")), None)
        if problem is None:
            found[key] = ("passed", "")
        else:
            found[key] = ("skipped" if problem.tag == "skipped" else "failed",
                          f"{problem.get('message', '')}\n{problem.text or ''}")
    return found


@pytest.mark.parametrize("case", guest_tests())
def test_in_the_vm(vm: boot.VmRun, case: str):
    if vm.status is None or not vm.text("junit.xml"):
        pytest.fail(f"the VM {'timed out' if vm.timed_out else 'ended'} after {vm.wall_s:.0f} s without the "
                    f"in-VM tests' results\n--- setup.log\n{vm.text('setup.log')[-3000:]}\n--- pytest.log\n"
                    f"{vm.text('pytest.log')[-3000:]}\n--- console\n{vm.text('console.log')[-3000:]}"
                    f"\n--- qemu\n{vm.text('qemu.log')[-2000:]}")
    outcome, text = outcomes(vm).get(case, ("missing", f"not in the in-VM results:\n{vm.text('pytest.log')[-3000:]}"))
    setup = "".join(line + "\n" for line in (vm.text("console.log") + vm.text("setup.log")).splitlines()
                    if "FAILED" in line or "failed" in line and line.startswith("vm-init"))
    assert outcome == "passed", f"in the VM ({vm.results}):\n{text}" + (f"\ndevice setup:\n{setup}" if setup else "")


def qemu_running(results: Path) -> list[int]:
    """The QEMU processes sharing `results` (from /proc)."""
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            command = Path(f"/proc/{entry}/cmdline").read_bytes()
        except OSError:
            continue  # ended while listed
        found += [int(entry)] if command.startswith(boot.QEMU.encode()) and str(results).encode() in command else []
    return found


def test_a_vm_that_outlives_its_timeout_is_killed(tmp_path):
    """Ended at the timeout (or when pytest is interrupted: the same finally), never left running."""
    reason = boot.qemu_missing()
    if reason:
        pytest.skip(f"the device test VM cannot run here: {reason}")
    done = boot.run(tmp_path, timeout_s=3.0)
    assert done.timed_out and done.status is None and done.wall_s < 15
    assert not qemu_running(tmp_path)


def test_qemu_ends_with_the_process_that_started_it_even_killed(tmp_path):
    reason = boot.qemu_missing()
    if reason:
        pytest.skip(f"the device test VM cannot run here: {reason}")
    starter = subprocess.Popen([sys.executable, str(Path(boot.__file__)), str(tmp_path)], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while not qemu_running(tmp_path) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert qemu_running(tmp_path), "QEMU did not start"
    finally:
        starter.kill()  # SIGKILL: no finally, no handler runs in it
        starter.wait()
    deadline = time.monotonic() + 10
    while qemu_running(tmp_path) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not qemu_running(tmp_path), "QEMU outlived the process that started it"
