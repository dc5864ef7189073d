"""mocap-wait-clock (edge/systemd), the gate the box services start behind, against a stand-in
for linuxptp's pmc that answers what ptp4l would, one answer per call from a script of reads."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

import layer_parse

SCRIPT = layer_parse.REPO / "edge" / "systemd" / "mocap-wait-clock"
pytestmark = pytest.mark.skipif(not shutil.which("awk"), reason="awk missing")

STATUS = """sending: GET TIME_STATUS_NP
\t001122.fffe.334455-0 seq 0 RESPONSE MANAGEMENT TIME_STATUS_NP
\t\tmaster_offset              {offset}
\t\tingress_time               1573207395044458838
\t\tgmPresent                  {gm}
\t\tgmIdentity                 001122.fffe.334455
"""
PORT = """sending: GET PORT_DATA_SET
\t001122.fffe.334455-1 seq 0 RESPONSE MANAGEMENT PORT_DATA_SET
\t\tportIdentity            001122.fffe.334455-1
\t\tportState               {state}
"""


def fake_pmc(tmp_path: Path, answers: list[str]) -> Path:
    """A pmc printing answers[n] on its n-th call (the last one again after)."""
    for i, text in enumerate(answers):
        (tmp_path / f"answer{i}").write_text(text)
    pmc = tmp_path / "pmc"
    pmc.write_text(f"""#!/bin/sh
n=$(cat {tmp_path}/calls 2>/dev/null || echo 0)
echo $((n + 1)) > {tmp_path}/calls
[ "$n" -ge {len(answers)} ] && n={len(answers) - 1}
cat {tmp_path}/answer$n
""")
    pmc.chmod(0o755)
    return pmc


def wait_clock(pmc: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(SCRIPT), "--interval", "0", *args], env={"PMC": str(pmc), "PATH": "/usr/bin:/bin"},
                          capture_output=True, text=True, timeout=30)


def calls(tmp_path: Path) -> int:
    return int((tmp_path / "calls").read_text())


def test_synchronised_after_enough_good_reads_in_a_row(tmp_path):
    answers = [STATUS.format(offset=o, gm=g) for o, g in
               [(0, "false"), (250000, "true"), (-90000, "true"), (500, "true"), (150000, "true")]]
    answers += [STATUS.format(offset=-40, gm="true")]
    result = wait_clock(fake_pmc(tmp_path, answers), "--stable", "3")
    assert result.returncode == 0, result.stderr
    assert calls(tmp_path) == 8  # reads 6, 7, 8 are the three good ones in a row after the last bad one
    assert "no grandmaster" in result.stdout and "offset 250000 ns" in result.stdout


def test_times_out_while_the_offset_stays_too_large(tmp_path):
    result = wait_clock(fake_pmc(tmp_path, [STATUS.format(offset=-200001, gm="true")]),
                        "--max-offset-ns", "200000", "--timeout", "2", "--interval", "1")
    assert result.returncode == 1 and "offset -200001 ns" in result.stderr
    assert calls(tmp_path) == 3  # at 0, 1 and 2 s


def test_no_answer_from_ptp4l_is_waited_for(tmp_path):
    result = wait_clock(fake_pmc(tmp_path, ["sending: GET TIME_STATUS_NP\n"]), "--timeout", "2", "--interval", "1")
    assert result.returncode == 1 and "no answer from ptp4l" in result.stderr


def test_the_grandmaster_waits_for_its_port_to_be_master(tmp_path):
    answers = [PORT.format(state=s) for s in ("LISTENING", "LISTENING", "MASTER")]
    result = wait_clock(fake_pmc(tmp_path, answers), "--grandmaster", "--stable", "1")
    assert result.returncode == 0 and calls(tmp_path) == 3


@pytest.mark.parametrize("args", [["--stable", "x"], ["--timeout"], ["--bogus"]])
def test_a_bad_argument_is_refused(tmp_path, args):
    result = wait_clock(fake_pmc(tmp_path, [STATUS.format(offset=0, gm="true")]), *args)
    assert result.returncode == 2 and "mocap-wait-clock:" in result.stderr


REAL_PTP = pytest.mark.skipif(not shutil.which("ptp4l") or not shutil.which("pmc") or os.geteuid() != 0,
                              reason="linuxptp (make setup) and root (PTP's ports 319 and 320) are needed")
SYSTEMD = layer_parse.REPO / "edge" / "systemd"


@REAL_PTP
@pytest.mark.parametrize("conf", ["ptp4l-box.conf", "ptp4l-grandmaster.conf"])
def test_ptp4l_reads_the_boxes_settings(tmp_path, conf):
    """This machine's linuxptp (Debian's 3.1; the image has 4.1, which reads these option names too)."""
    out = subprocess.run(["timeout", "2", "ptp4l", "-f", str(SYSTEMD / conf), "-i", "lo", "-m",
                          "--uds_address", str(tmp_path / "ptp4l")], capture_output=True, text=True, timeout=30)
    assert "INITIALIZING to LISTENING" in out.stdout + out.stderr, out.stdout + out.stderr


@REAL_PTP
def test_the_grandmaster_gate_with_a_real_ptp4l(tmp_path):
    """ptp4l with the grandmaster's settings on the loopback interface takes the grandmaster role
    once no other clock announces itself; the gate, asking the real pmc, opens then."""
    uds = tmp_path / "ptp4l"
    ptp4l = subprocess.Popen(["ptp4l", "-f", str(SYSTEMD / "ptp4l-grandmaster.conf"), "-i", "lo", "-m",
                              "--uds_address", str(uds)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        pmc = tmp_path / "pmc"
        pmc.write_text(f'#!/bin/sh\nexec {shutil.which("pmc")} -s {uds} "$@"\n')
        pmc.chmod(0o755)
        result = wait_clock(pmc, "--grandmaster", "--stable", "2", "--interval", "1", "--timeout", "20")
    finally:
        ptp4l.terminate()
        log, _ = ptp4l.communicate(timeout=10)
    assert result.returncode == 0, result.stdout + result.stderr + log
    assert "assuming the grand master role" in log
