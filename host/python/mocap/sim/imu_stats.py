"""Noise and bias figures of real IMU recordings (`mocap imu-stats`), behind sim/imu.py.

handheld/sensor_data.csv (gyroscope deg/s, accelerometer g, ~100 Hz): stationary blocks
are runs of at least 2 s whose gyroscope magnitude stays under 1 deg/s; per block, the
accelerometer's standard deviation per axis (white noise) and |a| - g (bias along gravity).
xsens-mtw-walking/*.txt (accelerometer m/s^2, orientation matrix, 100 Hz): per sensor,
over its quietest 0.5 s window (the smallest spread of |a|), the accelerometer's standard
deviation per axis and the median rotation from one orientation sample to the next.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap import rotations

G = 9.80665  # m/s^2


def handheld(path: Path) -> dict:
    d = np.genfromtxt(path, delimiter=",", skip_header=1)
    t, gyro, acc = d[:, 0], d[:, 1:4], d[:, 4:7] * G
    rate = 1.0 / np.median(np.diff(t))
    still = np.linalg.norm(gyro, axis=1) < 1.0
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0]))
    blocks = [(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a >= 2 * rate]
    if not blocks:
        return {"stationary_blocks": 0}
    return {"rate_hz": round(float(rate), 1), "stationary_blocks": len(blocks),
            "accel_noise_ms2": np.mean([acc[a:b].std(axis=0) for a, b in blocks], axis=0).round(4).tolist(),
            "accel_norm_bias_ms2": round(float(np.mean([np.linalg.norm(acc[a:b], axis=1).mean() - G
                                                         for a, b in blocks])), 4),
            "gyro_noise_dps": np.mean([gyro[a:b].std(axis=0) for a, b in blocks], axis=0).round(4).tolist()}


def xsens(folder: Path, window: int = 50) -> dict:
    out = {}
    for path in sorted(Path(folder).glob("*.txt")):
        data = np.genfromtxt(path, skip_header=5, delimiter="\t", names=True)
        acc = np.stack([data["Acc_X"], data["Acc_Y"], data["Acc_Z"]], axis=1)
        norm = np.linalg.norm(acc, axis=1)
        starts = range(0, len(acc) - window, window)
        best = min(starts, key=lambda i: norm[i:i + window].std())
        mats = np.stack([data[f"Mat{i}{j}"] for i in (1, 2, 3) for j in (1, 2, 3)], axis=1).reshape(-1, 3, 3)
        quiet = mats[best:best + window]
        step = np.degrees(rotations.angle_between(quiet[:-1], quiet[1:]))
        out[path.stem.split("_")[-1]] = {"accel_noise_ms2": acc[best:best + window].std(axis=0).round(4).tolist(),
                                         "accel_norm_ms2": round(float(norm[best:best + window].mean()), 4),
                                         "orientation_step_deg": round(float(np.median(step)), 4)}
    return out


def stats(imu_folder: Path) -> dict:
    return {"handheld": handheld(imu_folder / "handheld" / "sensor_data.csv"),
            "xsens_mtw_walking": xsens(imu_folder / "xsens-mtw-walking")}
