"""The hub's configuration, hub.toml: which CAN node and which I2C address is which of the
session's sensors, and the settings the hub sends the nodes (rate, ranges, mode) and runs by
(Syncs per second, batch period, when a sensor is stale). Values the nodes would refuse and a
CAN bus loaded above bus_budget.MAX_LOAD are refused when it is read."""

from __future__ import annotations

import dataclasses
import numbers
import tomllib
from pathlib import Path

from mocap_edge.errors import EdgeError
from mocap_edge.hub import bus_budget

MAX_FILE_BYTES = 1 << 20  # hub.toml is read whole


@dataclasses.dataclass
class HubConfig:
    """hub.toml: [hub] id, rate_hz, acc_range_g, gyro_range_dps, mode ("6d" or "9d"),
    sync_hz, batch_ms, stale_s, late_ms; [nodes] <node id> = "<sensor name>"; [i2c] "<address>" =
    "<sensor name>" (IMUs on the hub's own bus, e.g. "0x68" = "pelvis")."""
    names: dict[int, str]
    i2c: dict[int, str] = dataclasses.field(default_factory=dict)
    hub_id: str = "hub0"
    rate_hz: int = 60
    acc_range_g: int = 16
    gyro_range_dps: int = 2000
    mode: str = "6d"
    sync_hz: float = 100.0  # Syncs per second: p99 sample-time error 17 µs after 2 s (50: 31 µs; make bench)
    batch_ms: float = 10.0
    stale_s: float = 1.0  # a node silent this long is reported stale
    late_ms: float = 20.0  # a sample reaching the hub later than this after it was taken is counted late

    def __post_init__(self):
        """EdgeError for a value the nodes refuse, or a bus loaded above bus_budget.MAX_LOAD."""
        _check_types(self)
        problems = [what for bad, what in (
            (not 1 <= self.rate_hz <= 400, f"rate_hz {self.rate_hz} is not 1..400"),
            (self.acc_range_g not in (2, 4, 8, 16), f"acc_range_g {self.acc_range_g} is not 2, 4, 8 or 16"),
            (self.gyro_range_dps not in (250, 500, 1000, 2000),
             f"gyro_range_dps {self.gyro_range_dps} is not 250, 500, 1000 or 2000"),
            (self.mode not in ("6d", "9d"), f"mode {self.mode!r} is not \"6d\" or \"9d\""),
            (not self.sync_hz > 0 or not self.batch_ms > 0 or not self.stale_s > 0 or not self.late_ms > 0,
             "sync_hz, batch_ms, stale_s and late_ms are > 0"),
            (any(not 0x08 <= a <= 0x77 for a in self.i2c), "[i2c] addresses are 0x08..0x77"),
            (len({*self.names.values(), *self.i2c.values()}) != len(self.names) + len(self.i2c),
             "each sensor name once, across [nodes] and [i2c]")) if bad]
        load = bus_budget.check(len(self.names), self.rate_hz, self.sync_hz) if not problems else None
        if problems or load:
            raise EdgeError(f"hub configuration: {problems[0] if problems else load}")

    @classmethod
    def load(cls, path: Path) -> HubConfig:
        try:
            if Path(path).stat().st_size > MAX_FILE_BYTES:
                raise EdgeError(f"{path}: larger than {MAX_FILE_BYTES >> 10} KiB")
            data = tomllib.loads(Path(path).read_text())
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
            raise EdgeError(f"{path}: {e}") from None
        hub, nodes = data.get("hub", {}), data.get("nodes", {})
        bad_table = next((t for t in ("hub", "nodes", "i2c") if not isinstance(data.get(t, {}), dict)), None)
        if bad_table:
            raise EdgeError(f"{path}: [{bad_table}] is not a table")
        known = {f.name for f in dataclasses.fields(cls)} - {"names", "i2c", "hub_id"} | {"id"}
        unknown = sorted(set(hub) - known) + sorted(set(data) - {"hub", "nodes", "i2c"})
        if unknown:
            raise EdgeError(f"{path}: unknown key {unknown[0]!r}")
        if not all(isinstance(v, str) for v in [*nodes.values(), *data.get("i2c", {}).values()]):
            raise EdgeError(f"{path}: [nodes] and [i2c] values are sensor names (strings)")
        try:
            names = {int(k): str(v) for k, v in nodes.items()}
        except ValueError:
            raise EdgeError(f"{path}: [nodes] keys are node ids 1..63") from None
        if any(not 1 <= k <= 63 for k in names) or len(set(names.values())) != len(names):
            raise EdgeError(f"{path}: [nodes]: node ids 1..63, each sensor name once")
        try:
            i2c = {int(k, 0): str(v) for k, v in data.get("i2c", {}).items()}
        except ValueError:
            raise EdgeError(f"{path}: [i2c] keys are I2C addresses, e.g. \"0x68\"") from None
        settings = {("hub_id" if k == "id" else k): v for k, v in hub.items()}
        try:
            return cls(names, i2c, **settings)
        except EdgeError as e:
            raise EdgeError(f"{path}: {e}") from None

    def to_toml(self) -> str:
        """hub.toml's text for this configuration (load() reads it back)."""
        hub = {("id" if f.name == "hub_id" else f.name): getattr(self, f.name)
               for f in dataclasses.fields(self) if f.name not in ("names", "i2c")}
        lines = ["[hub]", *(f"{k} = {_toml_value(v)}" for k, v in hub.items()), "", "[nodes]",
                 *(f"{k} = {_toml_value(v)}" for k, v in sorted(self.names.items()))]
        if self.i2c:
            lines += ["", "[i2c]", *(f'"0x{k:02x}" = {_toml_value(v)}' for k, v in sorted(self.i2c.items()))]
        return "\n".join(lines) + "\n"


# The type of each setting of [hub]: a value of another type (a string rate, a boolean
# mode) is refused by name rather than failing a comparison.
_KINDS = {"hub_id": str, "rate_hz": numbers.Integral, "acc_range_g": numbers.Integral,
          "gyro_range_dps": numbers.Integral, "mode": str, "sync_hz": numbers.Real, "batch_ms": numbers.Real,
          "stale_s": numbers.Real, "late_ms": numbers.Real}


def _check_types(config: HubConfig) -> None:
    for name, kind in _KINDS.items():
        value = getattr(config, name)
        if not isinstance(value, kind) or isinstance(value, bool):
            raise EdgeError(f"hub configuration: {'id' if name == 'hub_id' else name} {value!r} is not "
                            f"{'a string' if kind is str else 'an integer' if kind is numbers.Integral else 'a number'}")


def _toml_value(value) -> str:
    """A TOML value: a basic string with every quote, backslash and control character escaped."""
    if not isinstance(value, str):
        return repr(value).replace("'", '"')
    escaped = "".join(f"\\u{ord(c):04x}" if c in '"\\' or ord(c) < 0x20 or ord(c) == 0x7F else c for c in value)
    return f'"{escaped}"'
