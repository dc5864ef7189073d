"""`mocap batch`: takes solved as Dask tasks give what `mocap solve --take` gives alone; a broken
take fails alone with its reason; a take solved before from the same inputs is skipped, a
changed one solved again; a cluster started as a user starts one (`dask scheduler`, `dask
worker`) runs the batch through --scheduler; a killed batch leaves no worker behind."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mocap.batch import inputs
from mocap.errors import InputError
from mocap.eval import balancing_take
from mocap.io.demo_data import BATCH_CACHE, TRIAL_CACHE, TRIAL_DONE
from mocap.io.take_folder import read_take
from mocap.recording import recorder
from mocap.sim import take_out
from mocap.takes import messages as take_messages

BIN = Path(sys.executable).parent
TIMEOUT_S = 600


def _mocap(*args, timeout=TIMEOUT_S, **kwargs):
    return subprocess.run([sys.executable, "-m", "mocap.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, **kwargs)


def _record(take_folder: Path, path: Path) -> Path:
    """The take's messages as a recording of a live take would hold them, its session attached
    (uncalibrated: the batch calibrates it from the recording)."""
    take = read_take(take_folder)
    session = take_messages.write_session(take, path.parent / f"{path.stem}_session")
    with recorder.Recorder(path) as r:
        r.attach_session(session)
        for arrival, type_name, payload in take_messages.messages(take):
            r.write([type_name.encode(), payload], arrival)
    return path


def _pose_files(take: Path) -> list[Path]:
    return sorted(p for p in take.rglob("*.json") if p.parent != take)  # the cameras' folders of OpenPose JSON


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    """Two simulated takes (3 s, their truth beside them), a broken copy of one (a pose file cut
    short) and a recording of the other's messages."""
    root = tmp_path_factory.mktemp("batch_takes")
    for name, seed in (("walk", 1), ("turn", 2)):
        take_out.run(root / name, seconds=3.0, preset="hq6", seed=seed)
    shutil.copytree(root / "walk", root / "broken")
    poses = _pose_files(root / "broken")
    pose = poses[len(poses) // 2]
    pose.write_text(pose.read_text()[:40])
    return {"walk": root / "walk", "turn": root / "turn", "broken": root / "broken", "pose": pose,
            "recording": _record(root / "turn", root / "turn_live.mcap")}


@pytest.fixture(scope="module")
def batch(takes, tmp_path_factory):
    out = tmp_path_factory.mktemp("batch_out")
    run = _mocap("batch", takes["walk"], takes["turn"], takes["broken"], takes["recording"], "--out", out,
                 "--workers", "2", "--export", "trc", "--export", "gltf")
    return out, run


def _results(out: Path) -> dict:
    return {r["name"]: r for r in json.loads((out / "summary.json").read_text())["results"]}


def test_a_batch_equals_the_serial_solves_and_a_broken_take_fails_alone(takes, batch, tmp_path):
    out, run = batch
    assert run.returncode == 1, run.stderr  # one take failed
    results = _results(out)
    assert {n: r["status"] for n, r in results.items()} == {"walk": "ok", "turn": "ok", "broken": "failed",
                                                            "turn_live": "ok"}
    assert takes["pose"].name in results["broken"]["error"] and "Traceback" not in run.stderr
    for name in ("walk", "turn"):
        alone = _mocap("solve", "--take", takes[name], "--out", tmp_path / name)
        assert alone.returncode == 0, alone.stderr
        for f in ("joints.csv", "take.bvh"):
            assert (out / name / f).read_bytes() == (tmp_path / name / f).read_bytes(), (name, f)
        # the report's estimates differ in their 14th digit: numpy's BLAS runs on one thread in a worker
        _assert_close(json.loads((out / name / "calibration.json").read_text()),
                      json.loads((tmp_path / name / "calibration.json").read_text()))
        assert results[name]["truth"]["joint_centres_pos_cm"] < 5.0
        assert (out / name / "take.trc").stat().st_size > 0 and (out / name / "take.glb").stat().st_size > 0
    assert results["turn_live"]["frames"] == read_take(takes["turn"]).n_frames
    assert (out / "turn_live" / "session" / "session.json").is_file()
    assert "| broken | failed |" in run.stdout and (out / "summary.md").read_text() == run.stdout


def _assert_close(a, b, path="report"):
    """The same JSON structure and strings, numbers within 1e-9 (relative)."""
    if isinstance(a, dict):
        assert sorted(a) == sorted(b), path
        for k in a:
            _assert_close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12), path
    else:
        assert a == b, path


def test_a_second_batch_skips_what_it_solved_and_solves_what_changed(takes, batch, tmp_path):
    out, _ = batch
    again, changed = tmp_path / "again", tmp_path / "turn"
    shutil.copytree(out, again)
    shutil.copytree(takes["turn"], changed)
    exports = ("--export", "trc", "--export", "gltf")
    run = _mocap("batch", takes["walk"], changed, "--out", again, "--workers", "1", *exports)
    assert run.returncode == 0, run.stderr
    results = _results(again)
    assert results["walk"]["skipped"] and results["turn"]["skipped"]  # the copy: the same bytes
    pose = _pose_files(changed)[0]
    pose.write_text(pose.read_text() + "\n")
    run = _mocap("batch", takes["walk"], changed, "--out", again, "--workers", "1", *exports)
    results = _results(again)
    assert run.returncode == 0 and results["walk"]["skipped"] and not results["turn"]["skipped"], run.stderr
    run = _mocap("batch", takes["walk"], "--out", again, "--workers", "1")  # other options: solved again
    assert run.returncode == 0 and not _results(again)["walk"]["skipped"], run.stderr


@pytest.fixture
def cluster(tmp_path):
    """`dask scheduler` and `dask worker` on loopback, as a user with a cluster starts them."""
    address_file = tmp_path / "scheduler.json"
    started = [subprocess.Popen([BIN / "dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                 "--scheduler-file", address_file], start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not address_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        started.append(subprocess.Popen([BIN / "dask", "worker", "--scheduler-file", address_file, "--nthreads", "1",
                                         "--no-dashboard"], start_new_session=True, stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL))
        yield json.loads(address_file.read_text())["address"]
    finally:
        for p in started[::-1]:
            os.killpg(p.pid, signal.SIGTERM)
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def test_a_batch_runs_on_a_cluster_given_its_scheduler(takes, batch, cluster, tmp_path):
    run = _mocap("batch", takes["walk"], "--out", tmp_path / "out", "--scheduler", cluster, "--export", "trc",
                 "--export", "gltf")
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "out" / "walk" / "joints.csv").read_bytes() == (batch[0] / "walk" / "joints.csv").read_bytes()


def _workers(pid: int) -> set[int]:
    """The Dask worker processes below pid (multiprocessing's spawned children)."""
    found, stack = set(), [pid]
    while stack:
        try:
            children = [int(c) for t in Path(f"/proc/{stack.pop()}/task").iterdir()
                        for c in (t / "children").read_text().split()]
            found |= {c for c in children if b"spawn_main" in Path(f"/proc/{c}/cmdline").read_bytes()}
        except (OSError, ValueError):
            continue  # ended while listed
        stack += children
    return found


def test_a_killed_batch_leaves_no_worker_behind(takes, tmp_path):
    batch = subprocess.Popen([sys.executable, "-m", "mocap.cli", "batch", takes["walk"], takes["turn"], "--out",
                              tmp_path, "--workers", "2"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline, workers = time.monotonic() + 120, set()
        while len(workers) < 2 and time.monotonic() < deadline:  # both worker processes are up
            workers = _workers(batch.pid)
            time.sleep(0.2)
        assert len(workers) == 2
    finally:
        batch.kill()
        batch.wait()
    deadline = time.monotonic() + 30
    while any(map(_alive, workers)) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [p for p in workers if _alive(p)]


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def test_what_is_no_take_is_refused_before_any_task(takes, tmp_path):
    (tmp_path / "empty").mkdir()
    for given, says in ((tmp_path / "nothing", "no such take folder or recording"),
                        (tmp_path / "empty", "no take.toml"), (takes["pose"], "neither a take folder")):
        run = _mocap("batch", given, "--out", tmp_path / "out")
        assert run.returncode == 2 and says in run.stderr and "Traceback" not in run.stderr
    run = _mocap("batch", takes["walk"], takes["walk"], "--out", tmp_path / "out")
    assert run.returncode == 2 and "given twice" in run.stderr


def test_takes_of_the_same_name_get_their_folders_name(tmp_path):
    for trial in ("Trial_1", "Trial_2"):
        (tmp_path / trial / "take").mkdir(parents=True)
        (tmp_path / trial / "take" / "take.toml").write_text("")
    names = [t.name for t in inputs.inputs([tmp_path / "Trial_1" / "take", tmp_path / "Trial_2" / "take"])]
    assert names == ["Trial_1_take", "Trial_2_take"]
    with pytest.raises(InputError, match="given twice"):
        inputs.inputs([tmp_path / "Trial_1" / "take", tmp_path / "Trial_1" / "take" / "."])


def test_an_unreachable_scheduler_is_named(takes, tmp_path):
    run = _mocap("batch", takes["walk"], "--out", tmp_path, "--scheduler", "tcp://127.0.0.1:9")
    assert run.returncode == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in run.stderr


@pytest.mark.skipif(not ((BATCH_CACHE / TRIAL_DONE).is_file() and (TRIAL_CACHE / TRIAL_DONE).is_file()),
                    reason="Pose2Sim's demo trials are not in .cache/ (python -m mocap.io.demo_data)")
def test_a_trial_of_videos_is_detected_and_solved_near_pose2sims_own_result(tmp_path):
    """Pose2Sim's batch demo, Trial_1 (the Balancing trial's videos; its calibration a Qualisys
    .qca.txt beside the trials): detected by the camera box's detector, solved, and compared
    with Pose2Sim's triangulation of the same trial."""
    run = _mocap("batch", BATCH_CACHE / "Trial_1", "--out", tmp_path, "--workers", "1")
    assert run.returncode == 0, run.stderr
    result = _results(tmp_path)["Trial_1"]
    assert result["detected"]["videos"] == 4 and result["frames"] == 100
    assert balancing_take.compare(TRIAL_CACHE, tmp_path / "Trial_1" / "joints.csv")["distance_cm"] < 6.0


def test_the_code_a_take_depends_on_decides_when_it_is_solved_again(tmp_path, monkeypatch):
    """A trial of videos depends on the detector's weights as well as the host's code; a take
    folder does not: new weights re-detect the trials and leave the take folders solved."""
    models = tmp_path / "blazepose"
    models.mkdir()
    (models / "pose_landmark_full.onnx").write_bytes(b"weights 1")
    monkeypatch.setattr(inputs.resources, "models_dir", lambda name: models)
    inputs.code_fingerprint.cache_clear()
    before = {kind: inputs.code_fingerprint(kind) for kind in (inputs.VIDEOS, inputs.TAKE)}
    (models / "pose_landmark_full.onnx").write_bytes(b"weights 2")
    inputs.code_fingerprint.cache_clear()
    after = {kind: inputs.code_fingerprint(kind) for kind in (inputs.VIDEOS, inputs.TAKE)}
    inputs.code_fingerprint.cache_clear()
    assert after[inputs.TAKE] == before[inputs.TAKE] and after[inputs.VIDEOS] != before[inputs.VIDEOS]
    assert before[inputs.TAKE] != before[inputs.VIDEOS]
