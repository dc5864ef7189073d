import subprocess
import sys

import pytest

from mocap import cli


def subcommands():
    parser = cli.build_parser()
    return list(parser._subparsers._group_actions[0].choices)


@pytest.mark.parametrize("command", [[]] + [[c] for c in subcommands()])
def test_every_subcommand_has_help(command):
    out = subprocess.run([sys.executable, "-m", "mocap.cli", *command, "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "usage: mocap" in out.stdout


def test_skeleton_from_a_bvh_file(tmp_path, shared):
    out = tmp_path / "skeleton.json"
    assert cli.main(["skeleton", "--from-bvh", str(shared / "data/mocap/xia/neutral_01_000.bvh"), "--out", str(out)]) == 0
    from mocap import _core

    skeleton = _core.Skeleton.load(str(out))
    assert skeleton.num_bones == 21 and 1.1 < skeleton.rest_height() < 1.8


def test_errors_are_reported_not_raised(tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("nonsense")
    assert cli.main(["skeleton", "--from-bvh", str(bad), "--out", str(tmp_path / "x.json")]) == 2
    assert "not a BVH file" in capsys.readouterr().err


def _run(capsys, *argv):
    """(exit status, stderr) of `mocap argv` run in this process: a traceback fails the test."""
    status = cli.main(list(argv))
    return status, capsys.readouterr().err


@pytest.fixture
def empty_recording(tmp_path):
    from mocap.recording import recorder

    with recorder.Recorder(tmp_path / "empty.mcap"):
        pass
    return tmp_path / "empty.mcap"


def test_replay_on_a_port_in_use_or_a_malformed_endpoint_names_it(capsys, empty_recording):
    import zmq

    with zmq.Context() as context, context.socket(zmq.PUB) as taken:
        port = taken.bind_to_random_port("tcp://127.0.0.1")
        endpoint = f"tcp://127.0.0.1:{port}"
        status, err = _run(capsys, "replay", str(empty_recording), "--bind", endpoint)
        assert status == 2 and err == f"mocap replay: {endpoint}: cannot publish there (Address already in use)\n"
    status, err = _run(capsys, "replay", str(empty_recording), "--bind", "tcp:/nonsense")
    assert status == 2 and err.startswith("mocap replay: tcp:/nonsense: cannot publish there ("), err


def test_record_from_a_malformed_endpoint_names_it_and_writes_nothing(capsys, tmp_path):
    out = tmp_path / "x.mcap"
    status, err = _run(capsys, "record", "--connect", "tcp://127.0.0.1:5999", "nonsense", "--out", str(out),
                       "--seconds", "0.1")
    assert status == 2 and err.startswith("mocap record: nonsense: cannot connect ("), err
    assert not out.exists()


@pytest.mark.parametrize("content", [b"{not json", bytes(range(256))])
def test_a_session_that_is_not_json_is_named(capsys, tmp_path, content):
    session = tmp_path / "session.json"
    session.write_bytes(content)
    status, err = _run(capsys, "record", "--connect", "tcp://127.0.0.1:5999", "--out", str(tmp_path / "x.mcap"),
                       "--seconds", "0.1", "--session", str(session))
    assert status == 2 and err.startswith(f"mocap record: {session}: not a JSON session file ("), err


def test_a_full_disk_names_the_output(capsys, tmp_path):
    from mocap import _core
    from mocap.io import calib_toml

    cam = _core.Camera()
    cam.name, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy = "c0", 640, 480, 500.0, 500.0, 320.0, 240.0
    (tmp_path / "Calib.toml").write_text(calib_toml.dumps(_core.Rig([cam])))
    status, err = _run(capsys, "rig", "--from-calib-toml", str(tmp_path / "Calib.toml"), "--out", "/dev/full")
    assert status == 2
    assert err == ("mocap rig: /dev/full: writing the output failed (No space left on device); what was written "
                   "is incomplete\n")
