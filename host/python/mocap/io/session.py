"""The host's session file: what mocapd solves and where the streams are (format
mocap.session/1, read by mocapd: host/daemon/session.h).

    {"format": "mocap.session/1",
     "skeleton": path, "rig": path, "layout": path, "imus": path, "prior": path or null,
     "inputs": ["tcp://edge-box-1:5600", ...], "output": "tcp://*:5700",
     "sync": {"max_wait_ms": 25, ...}, "solver": {"heading_time_constant": 1, ...},
     "imus_calibrated": true,
     "curve": {"host_key": "keys/host.key", "inputs": {"tcp://edge-box-1:5600": "Z85 public key", ...},
               "subscribers": ["Z85 public key", ...]}}

Paths are relative to the session file. `Session` is the one reader and writer of the
Python tools (the calibration, the demo's studio, a recording's attachment): it refuses
what mocapd refuses — an unknown key anywhere, a "sync" value that is not a number, a
"solver" object mocapd's own parser rejects (an unknown option, a value of the wrong type or
out of range) — so nothing written here is dropped or refused by mocapd. "sync" and "solver"
hold only the settings that differ from mocapd's defaults. "curve" (optional) holds the
streams' CURVE keys (`CurveSettings`; host/daemon/curve_keys.h); without it nothing is
authenticated, which mocapd allows only for inputs on this machine.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from mocap import _core
from mocap.errors import InputError
from mocap.net import keys

MAX_PEOPLE = 8  # a session's "people" (mocapd's kMaxPeople)
FORMAT = "mocap.session/1"
FILES = ("skeleton", "rig", "layout", "imus", "prior")  # the keys that name files


@dataclasses.dataclass
class SyncSettings:
    """The "sync" object: the synchroniser's times (ms) and its frame rate without cameras
    (Hz); None keeps mocapd's default (host/include/mocap/stream_sync.h). The fields are the
    keys mocapd reads (_core.session_sync_keys(); a test fails when they differ)."""
    group_tolerance_ms: float | None = None
    max_wait_ms: float | None = None
    stale_after_ms: float | None = None
    imu_max_gap_ms: float | None = None
    imu_max_hold_ms: float | None = None
    imu_history_ms: float | None = None
    imu_only_rate_hz: float | None = None

    def to_json(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if getattr(self, f.name) is not None}

    @classmethod
    def from_json(cls, data: Any, where: str) -> SyncSettings:
        if not isinstance(data, dict):
            raise InputError(f"{where}: sync must be an object")
        known = [f.name for f in dataclasses.fields(cls)]
        for key, value in data.items():
            if key not in known:
                raise InputError(f"{where}: unknown sync option '{key}' (known: {', '.join(known)})")
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"{where}: sync option '{key}' must be a number")
        return cls(**data)


@dataclasses.dataclass
class CurveSettings:
    """The "curve" object: the host's secret key file (relative to the session's folder), each
    input endpoint's server key, and (optional) the clients admitted on mocapd's output besides
    the host's own key (None: any client that knows the host's public key)."""
    host_key: str
    inputs: dict[str, str]
    subscribers: list[str] | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"host_key": self.host_key, "inputs": dict(self.inputs)}
        if self.subscribers is not None:
            out["subscribers"] = list(self.subscribers)
        return out

    @classmethod
    def from_json(cls, data: Any, inputs: list[str], where: str) -> CurveSettings:
        """Refuses what mocapd refuses: an unknown key, a key that is not 40 characters of
        Z85, a key for no input, an input without a key."""
        if not isinstance(data, dict):
            raise InputError(f"{where}: curve is an object")
        unknown = [k for k in data if k not in ("host_key", "inputs", "subscribers")]
        if unknown:
            raise InputError(f"{where}: unknown curve key '{unknown[0]}'")
        if not isinstance(data.get("host_key"), str):
            raise InputError(f"{where}: curve: host_key (the host's secret key file) is missing")
        given = data.get("inputs")
        if not isinstance(given, dict):
            raise InputError(f"{where}: curve: inputs (endpoint -> public key) is missing")
        for endpoint, key in given.items():
            if endpoint not in inputs:
                raise InputError(f"{where}: curve: key for '{endpoint}', which is not an input")
            if not keys.is_key(key):
                raise InputError(f"{where}: curve: the key of '{endpoint}' is not a public key "
                                 "(40 characters of Z85, as `mocap keys` writes)")
        missing = [e for e in inputs if e not in given]
        if missing:
            raise InputError(f"{where}: curve: no key for input '{missing[0]}'")
        subscribers = data.get("subscribers")
        if subscribers is not None and not isinstance(subscribers, list):
            raise InputError(f"{where}: curve: subscribers is a list of public keys")
        for key in subscribers or []:
            if not keys.is_key(key):
                raise InputError(f"{where}: curve: subscriber {json.dumps(key)} is not a public key")
        return cls(data["host_key"], dict(given), subscribers)


@dataclasses.dataclass
class Session:
    """A session file's contents. File names are as written (relative to `base`, the
    session file's folder, or absolute); `file(key)` resolves one."""
    skeleton: str
    rig: str
    layout: str
    imus: str
    inputs: list[str]  # every edge box, IMU hub and calibrator (PUB, bound there)
    output: str  # where mocapd publishes PoseFrame and Health
    prior: str | None = None  # None: no prior terms
    sync: SyncSettings = dataclasses.field(default_factory=SyncSettings)
    # The "solver" object: SolverOptions fields by name, a term's as {"term": {"field": value}}
    # (_core.session_solver_keys()); the ones absent keep mocapd's defaults.
    solver: dict[str, Any] = dataclasses.field(default_factory=dict)
    imus_calibrated: bool = True  # False: mocapd waits for a Calibration before using the IMUs
    curve: CurveSettings | None = None  # None: streams without keys
    people: int = 1  # the most performers solved at once (above 1: one PoseFrame each)
    # Several people: the suits that may be worn, {"imus": file, "skeleton": file (optional)} each
    # (mocapd finds who wears which from motion).
    suits: list[dict[str, str]] = dataclasses.field(default_factory=list)
    base: Path = dataclasses.field(default=Path("."), compare=False)  # not written

    def file(self, key: str) -> Path | None:
        """The file named under `key` (one of FILES), resolved against `base`; None for no prior."""
        name = getattr(self, key)
        return None if name is None else self.base / name

    def host_keys(self) -> keys.KeyPair | None:
        """The host's key pair (its secret key file read), or None without "curve"."""
        if self.curve is None:
            return None
        try:
            return keys.read_secret(self.base / self.curve.host_key)
        except keys.KeyFileError as e:
            raise InputError(f"session: {e}") from None

    def client_keys(self) -> keys.ClientKeys | None:
        """What a subscriber on the host uses (the recorder, the calibrator, the demo): the
        host's key pair, each input's server key; any other endpoint is taken for mocapd's
        output, whose server key is the host's. None without "curve"."""
        pair = self.host_keys()
        if pair is None:
            return None
        return keys.ClientKeys(pair, dict(self.curve.inputs), default=pair.public)

    def solver_options(self) -> _core.SolverOptions:
        """The solver options mocapd solves with: its defaults, then "solver"."""
        return _parse_solver(self.solver, "session")

    def with_solver(self, **settings: Any) -> Session:
        """A copy whose "solver" object has these settings too (SolverOptions fields by name)."""
        return dataclasses.replace(self, solver={**self.solver, **settings})

    def to_json(self) -> dict[str, Any]:
        self._check("session")
        out: dict[str, Any] = {"format": FORMAT}
        out.update({key: getattr(self, key) for key in FILES})
        out.update({"inputs": list(self.inputs), "output": self.output})
        if self.sync.to_json():
            out["sync"] = self.sync.to_json()
        if self.solver:
            out["solver"] = self.solver
        out["imus_calibrated"] = self.imus_calibrated
        if self.curve is not None:
            out["curve"] = self.curve.to_json()
        if self.people != 1:
            out["people"] = self.people
        if self.suits:
            out["suits"] = [dict(s) for s in self.suits]
        return out

    def dumps(self) -> str:
        return json.dumps(self.to_json(), indent=1)

    def save(self, path: str | Path) -> Path:
        """Writes the session file (its files are not copied: their names are written as they are)."""
        path = Path(path)
        path.write_text(self.dumps())
        return path

    @classmethod
    def from_json(cls, data: Any, base: Path = Path("."), where: str = "session") -> Session:
        """A session from its JSON object; InputError names what mocapd would refuse."""
        if not isinstance(data, dict):
            raise InputError(f"{where}: a session is a JSON object")
        known = ("format", *FILES, "inputs", "output", "sync", "solver", "imus_calibrated", "curve", "people", "suits")
        unknown = [key for key in data if key not in known]
        if unknown:
            raise InputError(f"{where}: unknown session key '{unknown[0]}'")
        if data.get("format") != FORMAT:
            raise InputError(f"{where}: format is not {FORMAT}")
        missing = [key for key in ("skeleton", "rig", "layout", "imus", "inputs", "output") if key not in data]
        if missing:
            raise InputError(f"{where}: no {', '.join(missing)}")
        session = cls(data["skeleton"], data["rig"], data["layout"], data["imus"], list(data["inputs"]),
                      data["output"], data.get("prior"), SyncSettings.from_json(data.get("sync", {}), where),
                      dict(data.get("solver", {})), data.get("imus_calibrated", True), None, data.get("people", 1),
                      list(data.get("suits", [])), Path(base))
        session._check(where)
        if "curve" in data:
            session.curve = CurveSettings.from_json(data["curve"], session.inputs, where)
        return session

    @classmethod
    def load(cls, path: str | Path) -> Session:
        path = Path(path)
        if not path.is_file():  # missing, a folder, or a FIFO (whose read would block)
            raise InputError(f"{path}: not found or not a regular file")
        try:
            data = json.loads(path.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise InputError(f"{path}: not a JSON session file ({e})") from None
        return cls.from_json(data, path.parent, str(path))

    def _check(self, where: str) -> None:
        names = [getattr(self, key) for key in FILES if key != "prior"]
        if not all(isinstance(n, str) and n for n in names) or not (self.prior is None or isinstance(self.prior, str)):
            raise InputError(f"{where}: the files ({', '.join(FILES)}) are named by strings (prior: or null)")
        if not self.inputs or not all(isinstance(i, str) for i in self.inputs) or not isinstance(self.output, str):
            raise InputError(f"{where}: inputs is a non-empty list of endpoints and output an endpoint")
        if not isinstance(self.imus_calibrated, bool):
            raise InputError(f"{where}: imus_calibrated is true or false")
        if not isinstance(self.people, int) or isinstance(self.people, bool) or not 1 <= self.people <= MAX_PEOPLE:
            raise InputError(f"{where}: people must be a whole number from 1 to {MAX_PEOPLE}")
        suit_keys = {"imus", "skeleton"}
        if self.suits and (self.people < 2 or not all(
                isinstance(s, dict) and "imus" in s and set(s) <= suit_keys and all(isinstance(v, str) for v in s.values())
                for s in self.suits)):
            raise InputError(f"{where}: suits are for several people, each {{\"imus\": file, \"skeleton\": file}}")
        SyncSettings.from_json(self.sync.to_json(), where)
        _parse_solver(self.solver, where)
        if self.curve is not None:
            CurveSettings.from_json(self.curve.to_json(), self.inputs, where)


def _parse_solver(solver: dict[str, Any], where: str) -> _core.SolverOptions:
    """The options of a "solver" object, parsed by mocapd's own reader."""
    try:
        return _core.SolverOptions.from_session_json(json.dumps(solver))
    except ValueError as e:
        raise InputError(f"{where}: solver: {e}") from None
