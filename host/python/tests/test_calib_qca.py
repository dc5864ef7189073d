"""A Qualisys .qca.txt read as Pose2Sim reads it: Pose2Sim's batch demo ships the Balancing
trial's Calib.qca.txt, and Pose2Sim's own conversion of it is the Calib_qualisys.toml the
Balancing trial ships; ours gives the same cameras. A damaged file names itself and its fault."""

import numpy as np
import pytest

from mocap.errors import InputError
from mocap.io import calib_qca, calib_toml
from mocap.io.demo_data import BATCH_CACHE, TRIAL_CACHE, TRIAL_DONE

QCA = BATCH_CACHE / "calibration" / "Calib.qca.txt"


@pytest.mark.skipif(not (QCA.is_file() and (TRIAL_CACHE / TRIAL_DONE).is_file()),
                    reason="Pose2Sim's demo trials are not in .cache/ (python -m mocap.io.demo_data)")
def test_the_qca_gives_the_cameras_pose2sims_conversion_gives():
    ours = calib_qca.load(QCA).cameras
    theirs = calib_toml.load(TRIAL_CACHE / "Calib_qualisys.toml").cameras
    assert [c.name for c in ours] == ["cam01", "cam02", "cam03", "cam04"] and len(theirs) == 4
    for a, b in zip(ours, theirs):
        assert (a.width, a.height) == (b.width, b.height)
        np.testing.assert_allclose([a.fx, a.fy, a.cx, a.cy], [b.fx, b.fy, b.cx, b.cy], atol=1e-6)
        np.testing.assert_allclose(a.distortion, b.distortion, atol=1e-9)
        np.testing.assert_allclose(np.asarray(a.rotation), np.asarray(b.rotation), atol=1e-6)
        np.testing.assert_allclose(a.translation, b.translation, atol=1e-6)


CAMERA = ('<camera active="1" model="{model}" serial="{serial}"><fov_video left="0" top="0" right="639" '
          'bottom="479"/><intrinsic focalLengthU="32000" focalLengthV="32000" centerPointU="20480" '
          'centerPointV="15360" radialDistortion1="0" radialDistortion2="0" tangentalDistortion1="0" '
          'tangentalDistortion2="0"/><transform r11="1" r12="0" r13="0" r21="0" r22="1" r23="0" r31="0" r32="0" '
          'r33="1" x="0" y="0" z="{z}"/></camera>')


def _qca(path, *cameras):
    path.write_text("<calibration><cameras>" + "".join(cameras) + "</cameras></calibration>")
    return path


def test_video_cameras_in_their_serials_order_and_a_camera_looks_down_its_z(tmp_path):
    path = _qca(tmp_path / "c.qca.txt", CAMERA.format(model="none", serial="cam10", z=3000),
                CAMERA.format(model="Miqus Video", serial="cam2", z=3000),
                CAMERA.format(model="Oqus 700", serial="cam1", z=3000))  # a marker camera: left out
    rig = calib_qca.load(path)
    assert [c.name for c in rig.cameras] == ["cam2", "cam10"]
    cam = rig.cameras[0]
    assert (cam.width, cam.height, cam.fx, cam.cx, cam.cy) == (640, 480, 500.0, 320.0, 240.0)
    # the camera 3 m above the origin, Qualisys's camera z pointing up: OpenCV's z points down,
    # so the origin is 3 m in front of it, at the image centre
    np.testing.assert_allclose(np.asarray(cam.rotation) @ [0, 0, 0] + cam.translation, [0, 0, 3.0], atol=1e-12)
    np.testing.assert_allclose(np.asarray(cam.rotation) @ [0, 0, 1.0], [0, 0, -1.0], atol=1e-12)


@pytest.mark.parametrize("text, says", [
    ("not xml", "not a Qualisys calibration"),
    ("<calibration><cameras></cameras></calibration>", "no video camera"),
    (CAMERA.format(model="none", serial="c", z="far").join(["<calibration><cameras>", "</cameras></calibration>"]),
     "attribute z is 'far'"),
    ("<calibration><cameras><camera model='none' serial='c'/></cameras></calibration>", "camera 'c': no <fov_video>"),
])
def test_a_damaged_qca_names_the_file_and_the_fault(tmp_path, text, says):
    (tmp_path / "bad.qca.txt").write_text(text)
    with pytest.raises(InputError, match=f"bad.qca.txt: .*{says}"):
        calib_qca.load(tmp_path / "bad.qca.txt")
