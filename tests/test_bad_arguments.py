"""mocapd's command line: a bad number is an argument error (exit 2, a message naming the
option), never a run without end (--duration) or a flood of Health lines (--health-period).
The arguments are checked before the session is read, so no session is needed."""

import subprocess

import pytest

from mocap.demo.play import MOCAPD


def _mocapd(*args: str) -> subprocess.CompletedProcess:
    if not MOCAPD.exists():
        pytest.skip("mocapd is not built (make build)")
    return subprocess.run([str(MOCAPD), "no-session.json", *args], capture_output=True, text=True, timeout=10)


@pytest.mark.parametrize("option, value", [
    ("--duration", "abc"), ("--duration", "-1"), ("--duration", "nan"), ("--duration", "inf"), ("--duration", "0"),
    ("--duration", "3s"), ("--health-period", "0"), ("--health-period", "-1"), ("--health-period", "abc"),
    ("--health-period", "0.01"), ("--realtime", "10abc"), ("--realtime", "1.5")])
def test_a_bad_number_is_an_argument_error(option, value):
    out = _mocapd(option, value)
    assert out.returncode == 2, out.stderr
    assert out.stderr.startswith(f"mocapd: {option} {value}: "), out.stderr


def test_an_option_without_its_value_is_named():
    out = _mocapd("--duration")
    assert out.returncode == 2 and out.stderr == "mocapd: --duration needs a value\n"


def test_good_numbers_pass_to_the_session():
    out = _mocapd("--duration", "0.5", "--health-period", "0.1", "--realtime", "10")
    assert out.returncode == 1 and out.stderr.startswith("mocapd: no-session.json: "), out.stderr
