"""Two real people (Pose2Sim's Demo_MultiPerson, four cameras) detected by the camera box's
detector and tracked by the host: each keeps one id from birth to the trial's end, every
camera's detection of them assigned to that id, and the solved poses reproject onto them."""

import json

import pytest

from mocap import cli
from mocap.io.demo_data import MULTI_CACHE, TRIAL_DONE


@pytest.mark.skipif(not (MULTI_CACHE / TRIAL_DONE).is_file(),
                    reason="Pose2Sim's multi-person trial is not in .cache/ (python -m mocap.io.demo_data)")
def test_two_real_people_keep_one_id_each_through_the_trial(tmp_path):
    out, sheet = tmp_path / "trial.json", tmp_path / "sheet.jpg"
    assert cli.main(["eval", "--multiperson-trial", "--json", str(out), "--sheet", str(sheet)]) == 0
    result = json.loads(out.read_text())
    # Measured: born on frame 4 (birth_frames 5), both through frame 99; 95% of the
    # detections assigned; reprojection median 13.3 px (1088 x 1920 images); with the person
    # detector looking for newcomers, camera 2 finds both people (1.96 per frame); camera 4
    # the woman standing behind the man too (2.0; 1.32 while a region near a tracked one was
    # taken for that person); camera 3 the woman standing far back on most frames, found in the
    # image's tiles (1.39; 0.92 from the whole image alone).
    assert result["subjects_born"] == 2 and result["retired"] == 0 and result["revivals"] == 0
    assert all(s["first_frame"] <= 6 and s["last_frame"] == result["frames"] - 1 for s in result["ids"].values())
    assert result["assigned_share"] > 0.9
    assert result["reprojection_px_median"] < 20.0
    assert result["people_per_frame_by_camera"][1] > 1.8 and result["people_per_frame_by_camera"][3] > 1.9
    assert result["people_per_frame_by_camera"][2] > 1.2
    assert sheet.stat().st_size > 50_000
