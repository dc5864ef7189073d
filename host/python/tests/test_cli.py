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
