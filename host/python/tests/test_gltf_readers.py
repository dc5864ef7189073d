"""The glTF export read by tools the project did not write: Blender's own importer (Debian's
`blender -b`) puts every bone's head, at every keyframe, where the solved skeleton's joint is
(within 1 mm, after the axes Blender's importer documents: glTF's Y up -> Blender's Z up, x, y, z
-> x, -z, y), and Khronos' glTF-Validator (npm, run with node) finds no error and no warning."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mocap import _core, paths
from mocap.io import retarget
from mocap.io.bvh_export import write_bvh

BLENDER = shutil.which("blender")
VALIDATOR = paths.REPO / "tests" / "node" / "validate_gltf.mjs"

GLTF_TO_BLENDER = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])


def _exported(folder: Path) -> tuple[_core.Skeleton, np.ndarray, Path]:
    """A solved-like motion of the default skeleton (10 frames at 60 Hz) written as BVH, exported
    by `mocap export --format gltf`: the skeleton, the poses, the .glb."""
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    rng = np.random.default_rng(2)
    thetas = np.zeros((10, skeleton.pose_dim))
    thetas[:, :3] = [0.3, -0.2, 1.0] + np.linspace(0, 1, 10)[:, None] * [0.5, 0.1, 0.05]
    thetas[:, 3:] = 0.4 * rng.normal(size=(1, skeleton.pose_dim - 3)) * np.linspace(0.2, 1, 10)[:, None]
    write_bvh(folder / "take.bvh", skeleton, thetas, 60.0)
    export = subprocess.run([sys.executable, "-m", "mocap.cli", "export", str(folder / "take.bvh"), "--format",
                             "gltf", "--out", str(folder / "take.glb")], capture_output=True, text=True)
    assert export.returncode == 0, export.stderr
    return skeleton, thetas, folder / "take.glb"


@pytest.mark.skipif(BLENDER is None, reason="Blender is not installed (make setup installs Debian's)")
def test_blender_imports_the_gltf_export_with_the_solved_joints(tmp_path):
    skeleton, thetas, glb = _exported(tmp_path)
    script = Path(__file__).with_name("blender_import_glb.py")
    run = subprocess.run([BLENDER, "-b", "--factory-startup", "--python-exit-code", "1", "--python", str(script),
                          "--", str(glb), str(tmp_path / "heads.json")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    imported = json.loads((tmp_path / "heads.json").read_text())
    assert len(imported["heads"]) == len(thetas), imported["frames"]
    ours_from_blender = retarget.P @ GLTF_TO_BLENDER.T  # Blender -> glTF -> our world (Z up)
    for k, (theta, heads) in enumerate(zip(thetas, imported["heads"])):
        _, expected = skeleton.forward_kinematics(theta)
        assert set(skeleton.bone_names) <= set(heads), sorted(heads)
        got = np.array([heads[b] for b in skeleton.bone_names]) @ ours_from_blender.T
        assert np.abs(got - expected).max() < 1e-3, (k, np.abs(got - expected).max())


@pytest.mark.skipif(shutil.which("node") is None or not (VALIDATOR.parent / "node_modules").is_dir(),
                    reason="node or the glTF validator is not installed (make setup: npm ci in tests/node)")
def test_khronos_validator_finds_no_issue_in_the_gltf_export(tmp_path):
    _, _, glb = _exported(tmp_path)
    run = subprocess.run(["node", str(VALIDATOR), str(glb)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    issues = json.loads(run.stdout)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
