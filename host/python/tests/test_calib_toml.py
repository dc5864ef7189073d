import numpy as np
import pytest

from mocap import rotations
from mocap.errors import InputError
from mocap.io import calib_toml

CALIB = """
[cam_01]
name = "cam_01"
size = [ 1920.0, 1080.0]
matrix = [ [ 1700.0, 0.0, 955.0], [ 0.0, 1690.0, 540.5], [ 0.0, 0.0, 1.0]]
distortions = [ -0.05, 0.02, 0.001, -0.002]
rotation = [ 1.2, -0.3, 0.25]
translation = [ 0.5, 0.9, 4.2]
fisheye = false

[metadata]
adjusted = false
error = 0.0
"""


def test_reads_the_pose2sim_layout(tmp_path):
    path = tmp_path / "Calib.toml"
    path.write_text(CALIB)
    rig = calib_toml.load(path)
    (cam,) = rig.cameras
    assert (cam.name, cam.width, cam.height) == ("cam_01", 1920, 1080)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (1700.0, 1690.0, 955.0, 540.5)
    assert list(cam.distortion) == [-0.05, 0.02, 0.001, -0.002, 0.0]
    np.testing.assert_allclose(cam.rotation, rotations.exp(np.array([1.2, -0.3, 0.25])), atol=1e-12)
    # The optical centre projects a point on the optical axis.
    on_axis = cam.center() + cam.rotation.T @ np.array([0, 0, 3.0])
    px, ok = cam.project(on_axis[None])
    assert ok[0] and np.allclose(px[0], [955.0, 540.5])


def test_refuses_fisheye_and_malformed(tmp_path):
    path = tmp_path / "Calib.toml"
    path.write_text(CALIB.replace("fisheye = false", "fisheye = true"))
    with pytest.raises(InputError, match="fisheye"):
        calib_toml.load(path)
    path.write_text(CALIB.replace("matrix", "matriz"))
    with pytest.raises(InputError, match="missing"):
        calib_toml.load(path)
    path.write_text("[cam")
    with pytest.raises(InputError):
        calib_toml.load(path)


@pytest.mark.parametrize("distortions, why", [
    ("[1e6, 0.0, 0.0, 0.0]", "a radial factor of"),  # pixels moved by metres, once used as given
    ("[-1.5, 0.0, 0.0, 0.0]", ""),  # the image folds back on itself inside the frame
    ("[-0.05, 0.02, 0.3, 0.0]", "tangential")])
def test_refuses_implausible_distortion(tmp_path, distortions, why):
    path = tmp_path / "Calib.toml"
    path.write_text(CALIB.replace("[ -0.05, 0.02, 0.001, -0.002]", distortions))
    with pytest.raises(InputError, match=rf"^{path}: camera 'cam_01': implausible distortion \(.*{why}"):
        calib_toml.load(path)


def test_refuses_two_tables_of_one_name(tmp_path):
    path = tmp_path / "Calib.toml"
    path.write_text(CALIB.replace("[metadata]", CALIB.split("[metadata]")[0].replace("[cam_01]", "[cam_02]")
                                  + "[metadata]"))
    with pytest.raises(InputError, match="two camera tables are named 'cam_01'"):
        calib_toml.load(path)
