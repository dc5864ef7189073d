"""One IMU's samples as an Xsens MT Manager export writes them, and the small delimited
tables of a take folder (sensors.csv).

A table: lines starting with `//` (MT Manager's header) and blank lines are skipped; the
first other line names the columns; the separator is a tab, `;` or `,` (the first of these
the header row contains). Columns are found by name, so their order is free and extra
columns are ignored. With `;` or tab separators a decimal comma (`0,49`) is read as a point.

An IMU file needs `PacketCounter`, `Acc_X, Acc_Y, Acc_Z` (m/s^2, sensor frame, gravity's
reaction included: +9.81 up at rest) and an orientation, sensor frame -> the sensor's
earth frame (Z up, heading its own): `Quat_q0..Quat_q3` (w, x, y, z), else the nine
`Mat[i][j]` (row i, column j of that rotation matrix, as MT Manager exports it). Times come
from `SampleTimeFine` (100 us ticks, tick 0 at the take's video frame 0), else, when that
column is absent or empty in every row, from `PacketCounter / rate`. PacketCounter wraps at
2^16 and SampleTimeFine at 2^32: both are unwrapped, and each must then increase strictly
(a step of half the modulus or more counts as going back).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap import rotations
from mocap.errors import TakeError

TICKS_PER_S = 10_000  # SampleTimeFine unit: 100 us
COUNTER_MODULUS, TICK_MODULUS = 1 << 16, 1 << 32
QUAT = ["Quat_q0", "Quat_q1", "Quat_q2", "Quat_q3"]
MAT = [f"Mat[{i}][{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]  # row-major
ACC = ["Acc_X", "Acc_Y", "Acc_Z"]
UNIT_TOLERANCE = 0.01  # |q| or det(Mat) this far from 1 is refused
MAX_FILE_BYTES = 256 << 20  # a table read whole (an hour of one IMU at 100 Hz: ~70 MB)


@dataclasses.dataclass
class Table:
    path: Path
    header_line: int  # 1-based line of the column names
    columns: list[str]
    rows: list[list[str]]
    lines: list[int]  # 1-based line of each row

    def index(self, names: list[str]) -> list[int]:
        """Column indices of `names`; a TakeError naming every missing one."""
        missing = [n for n in names if n not in self.columns]
        if missing:
            raise TakeError(self.path, f"missing column(s) {', '.join(missing)} (columns are {', '.join(self.columns)})",
                            self.header_line)
        return [self.columns.index(n) for n in names]

    def numbers(self, names: list[str]) -> np.ndarray:
        """(rows, len(names)) floats; a TakeError at the first empty, non-numeric or non-finite cell."""
        cols = self.index(names)
        cells = [[row[c] if c < len(row) else "" for c in cols] for row in self.rows]
        try:
            out = np.array(cells, dtype=float).reshape(len(self.rows), len(cols))
            if np.isfinite(out).all():
                return out
        except ValueError:
            pass
        for r, row in enumerate(cells):
            for c, cell in enumerate(row):
                try:
                    ok = np.isfinite(float(cell))
                except ValueError:
                    ok = False
                if not ok:
                    raise TakeError(self.path, f"column {names[c]}: {cell!r} is not a finite number", self.lines[r],
                                    cols[c] + 1)
        raise AssertionError("unreachable")


def read_table(path: Path) -> Table:
    try:
        if Path(path).stat().st_size > MAX_FILE_BYTES:
            raise TakeError(path, f"larger than {MAX_FILE_BYTES >> 20} MiB")
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as e:
        raise TakeError(path, f"cannot read: {e}") from None
    numbered = [(i + 1, ln.strip()) for i, ln in enumerate(text.splitlines())]
    numbered = [(i, ln) for i, ln in numbered if ln and not ln.startswith("//")]
    if not numbered:
        raise TakeError(path, "no header row")
    header_line, header = numbered[0]
    sep = next((s for s in ("\t", ";", ",") if s in header), ",")
    columns = [c.strip() for c in header.split(sep)]
    if len(set(columns)) != len(columns):
        raise TakeError(path, f"a column name appears twice: {columns}", header_line)
    rows = [[c.strip() for c in ln.split(sep)] for _, ln in numbered[1:]]
    if sep != ",":
        rows = [[c.replace(",", ".") for c in row] for row in rows]
    return Table(Path(path), header_line, columns, rows, [i for i, _ in numbered[1:]])


def unwrap(values: np.ndarray, modulus: int, table: Table, name: str) -> np.ndarray:
    """Unwrapped int64 counts; a TakeError at the first step that does not go forward."""
    if (values < 0).any() or (values >= modulus).any() or (values != np.round(values)).any():
        bad = int(np.argmax((values < 0) | (values >= modulus) | (values != np.round(values))))
        raise TakeError(table.path, f"{name} {values[bad]:g} is not an integer in [0, {modulus})", table.lines[bad],
                        table.columns.index(name) + 1)
    v = values.astype(np.int64)
    step = np.diff(v) % modulus
    back = np.flatnonzero((step == 0) | (step >= modulus // 2))
    if len(back):
        r = int(back[0]) + 1
        raise TakeError(table.path, f"{name} does not increase ({v[r - 1]} then {v[r]}, after unwrapping at {modulus})",
                        table.lines[r], table.columns.index(name) + 1)
    return v[0] + np.concatenate([[0], np.cumsum(step)])


@dataclasses.dataclass
class ImuSamples:
    packets: np.ndarray  # (N,) int64 PacketCounter, unwrapped
    times_s: np.ndarray  # (N,) s on the take's clock
    quaternions: np.ndarray  # (N, 4) w, x, y, z: sensor -> the sensor's earth frame
    accelerations: np.ndarray  # (N, 3) m/s^2, sensor frame, gravity's reaction included


def _orientations(table: Table) -> np.ndarray:
    if all(c in table.columns for c in QUAT) or not all(c in table.columns for c in MAT):
        q = table.numbers(QUAT)
        norm = np.linalg.norm(q, axis=1)
    else:
        m = table.numbers(MAT).reshape(-1, 3, 3)
        norm = np.linalg.det(m)
        q = rotations.quaternion_from_matrix(m)
    bad = np.flatnonzero(np.abs(norm - 1.0) > UNIT_TOLERANCE)
    if len(bad):
        raise TakeError(table.path, f"orientation is not a rotation (norm or determinant {norm[bad[0]]:.4g})",
                        table.lines[bad[0]])
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def read_imu(path: Path, rate: float | None) -> ImuSamples:
    """One MT Manager export; `rate` (Hz) times the samples when SampleTimeFine is absent."""
    table = read_table(path)
    if not table.rows:
        raise TakeError(path, "no samples", table.header_line)
    packets = unwrap(table.numbers(["PacketCounter"])[:, 0], COUNTER_MODULUS, table, "PacketCounter")
    col = table.columns.index("SampleTimeFine") if "SampleTimeFine" in table.columns else None
    if col is not None and any(col < len(r) and r[col] for r in table.rows):
        times = unwrap(table.numbers(["SampleTimeFine"])[:, 0], TICK_MODULUS, table, "SampleTimeFine") / TICKS_PER_S
    elif rate:
        times = packets / float(rate)
    else:
        raise TakeError(path, "no SampleTimeFine values, and no [imu] rate to time PacketCounter by",
                        table.header_line)
    return ImuSamples(packets, times, _orientations(table), table.numbers(ACC))


def write_imu(path: Path, times_s: np.ndarray, quaternions: np.ndarray, accelerations: np.ndarray,
              rate: float) -> None:
    """An MT Manager-style export (tab separated, `//` header). times_s are written as
    SampleTimeFine ticks (rounded to 100 us) and PacketCounter = round(t * rate), both wrapped."""
    ticks = np.round(np.asarray(times_s) * TICKS_PER_S).astype(np.int64)
    counter = np.round(np.asarray(times_s) * rate).astype(np.int64)
    head = (f"// Update Rate: {rate:g}Hz\n// Written by mocap (take folder, docs/take_format.md)\n"
            + "\t".join(["PacketCounter", "SampleTimeFine", *QUAT, *ACC]))
    data = np.column_stack([counter % COUNTER_MODULUS, ticks % TICK_MODULUS, quaternions, accelerations])
    np.savetxt(path, data, fmt=["%05d", "%d"] + ["%.9f"] * 4 + ["%.6f"] * 3, delimiter="\t", header=head,
               comments="")
