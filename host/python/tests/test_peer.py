"""`mocap bench --only peer`: our per-frame solve against Pose2Sim's triangulation. Our side
and the statistics are tested on a few frames of the real trial; Pose2Sim's side runs when
its virtual environment can be made here (PyPI), and is skipped with the reason otherwise."""

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mocap.eval import balancing_take, peer
from mocap.io.demo_data import TRIAL_CACHE, TRIAL_DONE
from mocap.recording import offline
from mocap.takes import solve as take_solve

FRAMES = 6
needs_trial = pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(), reason="the real trial is not in .cache/")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("peer")
    take = balancing_take.write(TRIAL_CACHE, folder / "take")
    return take_solve.calibrate(take, folder / "out")


@pytest.fixture(scope="module")
def pose2sim_python():
    try:
        return peer.environment()
    except peer.PeerUnavailable as e:
        pytest.skip(f"Pose2Sim's environment cannot be made here: {e}")


def test_statistics_are_the_per_frame_median_and_90th_percentile():
    s = peer.statistics([5.0, 1.0, 3.0, 2.0, 4.0, 6.0, 7.0, 8.0, 9.0, 10.0])
    assert s == {"frames": 10, "median_ms": 5.5, "p90_ms": 9.1, "mean_ms": 5.5, "max_ms": 10.0}
    best, medians = peer.best_of([[3.0, 3.0, 9.0], [2.0, 2.5, 30.0], [4.0, 4.0, 4.0]])
    assert medians == [3.0, 2.5, 4.0]
    assert best["median_ms"] == 2.5 and best["max_ms"] == 30.0  # the run with the lowest median, whole


@needs_trial
def test_our_side_times_the_solve_of_mocap_solve_take(calibrated):
    solved = peer.solve_timed(calibrated.session, calibrated.messages, 4, limit=FRAMES)
    host = offline.solve_messages(offline.pipeline_for(calibrated.session), calibrated.messages)
    assert len(solved) == FRAMES
    for ours, theirs in zip(solved, host):  # the same poses as the host's pipeline publishes
        np.testing.assert_allclose(ours.theta, theirs.theta, atol=1e-9)
        assert ours.wall_ms >= ours.solve_time_ms > 0  # the call wraps the solver's own timing
    for f, s in enumerate(solved):  # each camera's keypoints: one of its persons in the take's file,
        for c, persons in enumerate(calibrated.take.people):  # as the wire carries them (float32)
            if np.isnan(s.keypoints[c]).all():
                continue
            assert any(np.array_equal(s.keypoints[c], p.astype(np.float32)) for p in persons[f]), (f, c)
    assert sum(not np.isnan(s.keypoints).all() for s in solved) == FRAMES


@needs_trial
def test_the_line_says_why_pose2sims_side_was_skipped(calibrated, tmp_path):
    line = peer.measure(calibrated, TRIAL_CACHE / "Calib_qualisys.toml", repeats=2, limit=FRAMES,
                        python=tmp_path / "no-python")
    assert line["bench"] == "peer" and "no-python" in line["skipped"] and "pose2sim" not in line
    ours = line["ours"]
    assert ours["frames"] == FRAMES and len(ours["medians_ms_of_repeats"]) == 2
    assert ours["median_ms"] == min(ours["medians_ms_of_repeats"]) and ours["p90_ms"] >= ours["median_ms"]
    assert 0 < ours["cpu_median_ms"] <= ours["cpu_p90_ms"]
    assert ours["statuses"] == {"initialised": 1, "ok": FRAMES - 1}


def test_an_environment_that_cannot_be_made_is_reported(tmp_path):
    requirements = tmp_path / "requirements.txt"
    requirements.write_text(str(tmp_path / "no-such-package-1.0-py3-none-any.whl") + "\n")
    with pytest.raises(peer.PeerUnavailable, match="no-such-package"):
        peer.environment(tmp_path / "venv", requirements)
    assert not (tmp_path / "venv" / ".complete").exists()


def test_the_subprocess_is_pinned_and_dies_with_its_parent(tmp_path):
    note = tmp_path / "child"
    child = f"import os, time; open({str(note)!r}, 'w').write(f'{{os.getpid()}} {{sorted(os.sched_getaffinity(0))}}'); " \
            "time.sleep(60)"
    core = max(os.sched_getaffinity(0))
    parent = subprocess.Popen([sys.executable, "-c", f"from mocap.eval import peer; "
                               f"peer._run([{sys.executable!r}, '-c', {child!r}], 120, {core})"])
    try:
        for _ in range(600):
            if note.is_file() and note.read_text():
                break
            time.sleep(0.05)
        pid, affinity = note.read_text().split(" ", 1)
        assert affinity == f"[{core}]"
    finally:
        parent.kill()
        parent.wait()
    for _ in range(100):
        if not _alive(int(pid)):
            break
        time.sleep(0.05)
    assert not _alive(int(pid))


def _alive(pid: int) -> bool:
    status = Path(f"/proc/{pid}/status")
    try:
        return "\nState:\tZ" not in status.read_text()
    except FileNotFoundError:
        return False


@needs_trial
def test_pose2sims_own_triangulation_is_timed_on_our_frames(calibrated, pose2sim_python):
    n = 15  # triangulate_all keeps runs of more than 10 triangulated frames (its min_chunk_size)
    solved = peer.solve_timed(calibrated.session, calibrated.messages, 4, limit=n)
    keypoints = np.array([s.keypoints for s in solved])
    result = peer.pose2sim(keypoints, TRIAL_CACHE / "Calib_qualisys.toml", repeats=2, python=pose2sim_python)
    assert result["pose2sim"] == peer.VERSION and result["frames"] == n and result["keypoints"] == 21
    for key in ("per_frame_ms", "per_frame_cpu_ms"):
        assert len(result[key]) == 2 and all(len(r) == n for r in result[key])
    assert result["points_triangulated"] > 0.9 * n * 21
    # Pose2Sim's own triangulate_all on the same frames finds the same points: the driver
    # calls its per-frame functions as it does.
    check = result["triangulate_all"]
    assert check["points_compared"] == result["points_triangulated"] and check["max_difference_mm"] < 1e-6
    line = peer.theirs(result)
    assert line["median_ms"] == min(line["medians_ms_of_repeats"])
