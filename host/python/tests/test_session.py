"""The session file has one Python reader and writer (mocap.io.session.Session), used by every
Python writer; what it writes, mocapd's reader (C++ LoadSession, through the bindings'
HostPipeline.load) reads, and every option in it reaches mocapd: nothing is dropped."""

import dataclasses
import json

import numpy as np
import pytest

from mocap import _core, paths
from mocap.calibration.from_messages import Estimated, write_session
from mocap.errors import InputError
from mocap.io.session import Session, SyncSettings
from mocap.model import studio
from mocap.model.solver import imu_set_json, layout_json
from mocap.net import wire
from mocap.recording import reader, recorder


@pytest.fixture
def session(tmp_path) -> Session:
    """A session of the default skeleton, an 8-camera ring, the 13-IMU set and the prior,
    its files beside it (the rig's and IMU set's written here, the others by absolute path)."""
    (tmp_path / "rig.json").write_text(studio.ring_rig(8).to_json())
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    imus = _core.load_imu_sites(str(paths.IMU_SETS["13"]), skeleton)
    (tmp_path / "imus.json").write_text(json.dumps(imu_set_json(skeleton, imus)))
    return Session(str(paths.DEFAULT_SKELETON), "rig.json", str(paths.LAYOUTS / "blazepose33.json"), "imus.json",
                   ["tcp://127.0.0.1:5600"], "tcp://127.0.0.1:5700", prior=str(paths.HOST_DATA / "prior_default.json"),
                   base=tmp_path)


def _changed(value):
    """A valid value other than an option's default (mocapd's IsValid accepts each)."""
    if isinstance(value, bool):
        return not value
    if value is None:  # unknown (floor_height: null, NaN in the solver): a known value
        return 0.05
    if isinstance(value, int):
        return value + 1
    if isinstance(value, float):
        return 1.5 * value if value else 0.5
    if isinstance(value, str):  # a loss
        return "huber" if value != "huber" else "cauchy"
    if isinstance(value, list):  # accel_at_rest
        return [v + 0.01 for v in value]
    return {k: _changed(v) for k, v in value.items()}  # a term's fields


def _flat(solver: dict) -> dict:
    """A "solver" object's values by session key (a term's field as term.field)."""
    return {f"{k}.{f}" if f else k: (v[f] if f else v) for k, v in solver.items()
            for f in (v if isinstance(v, dict) else [None])}


def every_option_changed() -> dict:
    """The "solver" object with every field mocapd reads set away from its default."""
    return {k: _changed(v) for k, v in json.loads(_core.SolverOptions().to_session_json()).items()}


def test_the_sync_settings_are_the_keys_mocapd_reads():
    assert [f.name for f in dataclasses.fields(SyncSettings)] == list(_core.session_sync_keys())


def test_a_session_written_in_python_is_read_by_mocapd_with_every_option(session, tmp_path):
    solver = every_option_changed()
    sync = SyncSettings(group_tolerance_ms=5, max_wait_ms=30, stale_after_ms=400, imu_max_gap_ms=50,
                        imu_max_hold_ms=20, imu_history_ms=1500, imu_only_rate_hz=50)
    written = dataclasses.replace(session, solver=solver, sync=sync, imus_calibrated=False, people=3)
    path = written.save(tmp_path / "session.json")
    pipeline = _core.HostPipeline.load(str(path))  # mocapd's own reader: refuses any unknown key
    assert pipeline.skeleton.num_bones == 21
    read = Session.load(path)
    assert read == written and read.base == tmp_path
    # Every solver option reaches mocapd's options as written (its parser, its defaults under them).
    assert set(_flat(solver)) == set(_core.session_solver_keys())
    got = _flat(json.loads(read.solver_options().to_session_json()))
    for key, value in _flat(solver).items():
        assert got[key] == (pytest.approx(value) if isinstance(value, (float, list)) else value), key


@pytest.mark.parametrize("key", list(_core.session_sync_keys()))
def test_every_sync_key_reaches_mocapd(session, tmp_path, key):
    """A sync value out of range makes mocapd refuse the session: the key is read, not dropped."""
    path = dataclasses.replace(session, sync=SyncSettings(**{key: -1.0})).save(tmp_path / "session.json")
    with pytest.raises(ValueError, match="sync options out of range"):
        _core.HostPipeline.load(str(path))


@pytest.mark.parametrize("edit, message", [
    ({"colour": "red"}, "unknown session key 'colour'"),
    ({"sync": {"max_wait": 25}}, "unknown sync option 'max_wait'"),
    ({"sync": {"max_wait_ms": "25"}}, "must be a number"),
    ({"solver": {"max_iteration": 3}}, "unknown key 'max_iteration'"),
    ({"solver": {"max_iterations": 0}}, "solver"),
    ({"format": "mocap.session/2"}, "format"),
    ({"inputs": []}, "inputs"),
    ({"people": 0}, "people must be a whole number from 1 to 8"),
    ({"people": 9}, "people must be a whole number from 1 to 8"),
    ({"people": True}, "people must be a whole number from 1 to 8"),
    ({"suits": [{"imus": "suit.json"}]}, "suits are for several people"),
    ({"people": 2, "suits": [{"imus": "suit.json", "colour": "red"}]}, "suits are for several people, each"),
])
def test_what_mocapd_refuses_the_reader_refuses(session, tmp_path, edit, message):
    path = tmp_path / "session.json"
    path.write_text(json.dumps(session.to_json() | edit))
    with pytest.raises(ValueError):
        _core.HostPipeline.load(str(path))
    with pytest.raises(InputError, match=message):
        Session.load(path)
    with pytest.raises(InputError):  # nor does it write one
        Session.from_json(session.to_json() | edit, tmp_path).save(tmp_path / "again.json")


def test_the_calibration_writes_a_session_mocapd_reads(session, tmp_path):
    source = session.save(tmp_path / "session.json")
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "blazepose33.json"), skeleton)
    imus = _core.load_imu_sites(str(paths.IMU_SETS["6"]), skeleton)
    estimated = Estimated(skeleton.to_json(), json.dumps(imu_set_json(skeleton, imus)),
                          json.dumps(layout_json(skeleton, layout)), {"frames": 1})
    write_session(tmp_path / "out", source, estimated, {"frames": 1})
    out = tmp_path / "out" / "session.json"
    _core.HostPipeline.load(str(out))
    calibrated = Session.load(out)
    assert (calibrated.skeleton, calibrated.imus, calibrated.layout, calibrated.rig) == \
        ("skeleton.json", "imus.json", "layout.json", "rig.json")
    assert calibrated.imus_calibrated and calibrated.solver_options().heading_time_constant > 0
    assert calibrated.inputs == session.inputs and calibrated.file("prior").is_file()
    assert np.isnan(calibrated.solver_options().floor_height)  # the window saw no floor: E_G off
    # A floor the window found (calibration.window's report) is the calibrated session's.
    estimated.report["window"] = {"floor_height_m": 0.043}
    write_session(tmp_path / "floor", source, estimated, estimated.report)
    assert Session.load(tmp_path / "floor" / "session.json").solver_options().floor_height == 0.043


def test_a_recording_carries_its_session(session, tmp_path):
    source = session.save(tmp_path / "session.json")
    with recorder.Recorder(tmp_path / "take.mcap") as r:
        r.attach_session(source)
        r.write(wire.encode(wire.Health(source="x")), 1)
    (tmp_path / "attached").mkdir()
    extracted = reader.read_session(tmp_path / "take.mcap", tmp_path / "attached")
    assert extracted is not None and Session.load(extracted).skeleton == "skeleton.json"
    pipeline = _core.HostPipeline.load(str(extracted))
    assert np.allclose(pipeline.skeleton.offsets, _core.Skeleton.load(str(paths.DEFAULT_SKELETON)).offsets)
