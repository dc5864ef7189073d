"""The node's orientation filter through ctypes (mocap.imu_node.filter), `mocap imu-filter`
on CSV recordings, and its BROAD figures (mocap.imu_node.broad, needs ../shared)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from mocap import cli
from mocap.imu_node import filter as node_filter

RATE_HZ = 200.0
FIELD_ENU_UT = np.array([0.0, 20.0, -42.0])


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """q v q* for a unit quaternion w, x, y, z."""
    w, u = q[0], q[1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _still_recording(q_true: np.ndarray, seconds: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """t and (n, 9) samples of a still, noisy sensor at orientation q_true (sensor -> ENU)."""
    rng = np.random.default_rng(seed)
    n = int(seconds * RATE_HZ)
    conj = q_true * np.array([1.0, -1.0, -1.0, -1.0])
    acc = _rotate(conj, np.array([0.0, 0.0, 9.81]))
    mag = _rotate(conj, FIELD_ENU_UT)
    samples = np.hstack([np.zeros((n, 3)), np.tile(acc, (n, 1)), np.tile(mag, (n, 1))])
    samples += rng.normal(0.0, 1.0, samples.shape) * np.repeat([0.002, 0.03, 0.3], 3)
    return np.arange(n) / RATE_HZ, samples


def _angle_deg(q_a: np.ndarray, q_b: np.ndarray) -> float:
    return float(np.degrees(2.0 * np.arccos(min(1.0, abs(float(np.dot(q_a, q_b)))))))


def _q(angle_deg: float, axis: tuple[float, float, float]) -> np.ndarray:
    axis_v = np.array(axis) / np.linalg.norm(axis)
    half = np.radians(angle_deg) / 2.0
    return np.concatenate([[np.cos(half)], np.sin(half) * axis_v])


def _write_csv(path: Path, t: np.ndarray, samples: np.ndarray, header: str = ",".join(node_filter.CSV_COLUMNS)) -> None:
    with path.open("w") as f:
        f.write(header + "\n")
        for time, row in zip(t, samples):
            f.write(",".join(f"{v:.9g}" for v in [time, *row]) + "\n")


def test_settings_mirror_the_c_struct_and_can_be_changed():
    # Fixture / Test: the library's defaults through the size-checked mirror.
    settings = node_filter.default_settings()
    t, samples = _still_recording(_q(30.0, (1.0, 0.0, 0.0)), 1.0)
    bad = node_filter.default_settings()
    bad.acc_time_constant_s = -1.0
    # Assert: plausible defaults (units in the C header) and refused invalid settings.
    assert node_filter.library().imu_filter_batch_settings_size() == node_filter.ctypes.sizeof(node_filter.Settings)
    assert 1.0 <= settings.acc_time_constant_s <= 10.0
    assert settings.mag_rejection_enabled
    with pytest.raises(node_filter.InputError, match="refused its settings"):
        node_filter.run(samples[:, :3], samples[:, 3:6], None, 1.0 / RATE_HZ, bad)


def test_still_sensor_gives_its_orientation_in_9d_and_its_tilt_in_6d():
    # Fixture: a sensor turned 50 degrees about a skew axis, still for 8 s.
    q_true = _q(50.0, (1.0, -2.0, 0.5))
    t, samples = _still_recording(q_true, 8.0)
    # Test
    result9 = node_filter.run(samples[:, :3], samples[:, 3:6], samples[:, 6:9], 1.0 / RATE_HZ)
    result6 = node_filter.run(samples[:, :3], samples[:, 3:6], None, 1.0 / RATE_HZ)
    # Assert: 9D within 0.5 degrees of the truth; 6D's gravity direction within 0.5 degrees.
    assert _angle_deg(result9.quaternions[-1], q_true) < 0.5
    down_true = _rotate(q_true * [1, -1, -1, -1], np.array([0.0, 0.0, 1.0]))
    down_6d = _rotate(result6.quaternions[-1].astype(float) * [1, -1, -1, -1], np.array([0.0, 0.0, 1.0]))
    assert np.degrees(np.arccos(np.clip(down_true @ down_6d, -1, 1))) < 0.5
    assert result9.flags[-1] & node_filter.FLAG_SETTLED and not result9.flags[0] & node_filter.FLAG_SETTLED
    assert result9.rejected == 0


def test_cli_round_trip_on_a_csv_recording(tmp_path, capsys):
    # Fixture: a 6 s still recording with a NaN row in the middle.
    q_true = _q(120.0, (0.3, 1.0, -0.4))
    t, samples = _still_recording(q_true, 6.0, seed=1)
    samples[500, 3] = np.nan
    source, out, out6 = tmp_path / "in.csv", tmp_path / "out.csv", tmp_path / "out6.csv"
    _write_csv(source, t, samples)
    # Test
    code9 = cli.main(["imu-filter", "--in", str(source), "--out", str(out)])
    code6 = cli.main(["imu-filter", "--in", str(source), "--out", str(out6), "--no-mag"])
    # Assert: one unit quaternion row per input row, t kept, the last one the truth.
    assert (code9, code6) == (0, 0)
    assert '"rejected_vectors": 1' in capsys.readouterr().out
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t", "qw", "qx", "qy", "qz"]
    table = np.array(rows[1:], float)
    assert table.shape == (len(t), 5)
    np.testing.assert_allclose(table[:, 0], t, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(table[:, 1:], axis=1), 1.0, atol=1e-5)
    assert _angle_deg(table[-1, 1:], q_true) < 0.5
    assert len(out6.read_text().splitlines()) == len(t) + 1


@pytest.mark.parametrize("edit, message", [
    (lambda lines: [lines[0].replace(",mz", "")] + lines[1:], ":1: missing column(s) mz"),
    (lambda lines: lines[:3] + [lines[3].replace(lines[3].split(",")[4], "abc", 1)] + lines[4:], ":4: not a number"),
    (lambda lines: lines[:5] + [lines[4]] + lines[6:], ":6: t does not increase"),
    (lambda lines: lines[:5] + lines[6:], ":6: irregular sampling"),
    (lambda lines: lines[:3] + ["nan" + lines[3][lines[3].index(","):]] + lines[4:], ":4: t is not a finite number"),
    (lambda lines: lines[:2] + [lines[2] + ",1"] + lines[3:], ":3: 11 values, the header has 10"),
])
def test_cli_refuses_malformed_csv_naming_the_line(tmp_path, capsys, edit, message):
    # Fixture: a valid recording, then one fault.
    t, samples = _still_recording(_q(10.0, (0.0, 0.0, 1.0)), 0.2)
    source = tmp_path / "in.csv"
    _write_csv(source, t, samples)
    source.write_text("\n".join(edit(source.read_text().splitlines())) + "\n")
    # Test
    code = cli.main(["imu-filter", "--in", str(source), "--out", str(tmp_path / "out.csv")])
    # Assert: exit 2, the message names the file and line, no output file.
    assert code == 2
    assert f"{source}{message}" in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()


def test_missing_library_says_how_to_build_it(monkeypatch, tmp_path):
    # Fixture: the library path pointing nowhere, nothing loaded yet.
    monkeypatch.setattr(node_filter, "LIBRARY", tmp_path / "libmocap_node.so")
    monkeypatch.setattr(node_filter, "_lib", None)
    # Test / Assert
    with pytest.raises(node_filter.LibraryMissingError, match="run make build"):
        node_filter.default_settings()


def test_broad_metric_reproduces_the_manifest_vqf_figures(shared):
    # Fixture: all 18 trials. Test: VQF 9D through our metric.
    from mocap.imu_node import broad

    rows = broad.evaluate(broad.load(root=shared / "data" / "imu" / "broad"), ["VQF 9D"])
    summary = broad.summarise(rows, rows)
    # Assert: the MANIFEST's figures (total / heading / inclination).
    np.testing.assert_allclose(summary["undisturbed"]["VQF 9D"], (1.84, 1.67, 0.67), atol=0.006)
    np.testing.assert_allclose(summary["disturbed"]["VQF 9D"], (2.42, 2.27, 0.83), atol=0.006)


def test_broad_held_out_trials_meet_the_targets(shared):
    # Fixture: two held-out trials, one undisturbed, one disturbed (tapping).
    from mocap.imu_node import broad

    trials = broad.load(["02", "25"], root=shared / "data" / "imu" / "broad")
    # Test
    rows = broad.evaluate(trials, ["ours 9D", "VQF 9D"])
    # Assert: total within 2.0 (undisturbed) and 4.5 (disturbed) degrees, inclination
    # within 0.9, and within 10 % of VQF's total on the same trial.
    assert rows["02"]["ours 9D"][0] <= 2.0 and rows["25"]["ours 9D"][0] <= 4.5
    assert all(rows[n]["ours 9D"][2] <= 0.9 for n in rows)
    assert all(rows[n]["ours 9D"][0] <= 1.1 * rows[n]["VQF 9D"][0] for n in rows)
