"""The firmware's benchmark line: flash and RAM of the production node's image, the
orientation filter's instructions per sample on the production CPU's core (Cortex-M4F in
QEMU, -icount shift=0), and the filter's figures on the BROAD benchmark.

    mocap bench --only firmware
"""

from __future__ import annotations

import json

import numpy as np

from mocap.errors import DataMissingError
from mocap.imu_node import broad, qemu

PRODUCTION_BOARD = "stm32g431kb"
ICOUNT_TRIAL = "01"  # a whole BROAD trial (57,000 samples at 286 Hz) when ../shared is there


def image_size() -> dict:
    """Flash and RAM of the production image, as its build measured them."""
    path = qemu.boards_dir() / PRODUCTION_BOARD / "size.json"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: run `make build`")
    size = json.loads(path.read_text())
    keep = ("flash_bytes", "ram_bytes", "flash_budget_bytes", "ram_budget_bytes", "within_budget")
    return {key: size[key] for key in keep if key in size}


def _synthetic_recording(seconds: float = 60.0, rate_hz: float = 1000.0):
    """A turning, wobbling sensor with gravity, a 50 uT field and noise: for the cost when
    no real recording is at hand (the cost hardly depends on the motion)."""
    rng = np.random.default_rng(7)
    t = np.arange(int(seconds * rate_hz)) / rate_hz
    gyr = np.stack([0.8 * np.sin(1.3 * t), 0.5 * np.cos(0.7 * t), 1.5 * np.sin(0.4 * t)], axis=1)
    angle = np.cumsum(gyr, axis=0) / rate_hz
    acc = np.stack([9.81 * np.sin(angle[:, 1]), -9.81 * np.sin(angle[:, 0]), 9.81 * np.cos(angle[:, 0])], axis=1)
    mag = np.stack([20 * np.cos(angle[:, 2]), -20 * np.sin(angle[:, 2]), -45 + 0 * t], axis=1)
    noisy = [(x + rng.normal(0, s, x.shape)).astype(np.float32) for x, s in ((gyr, 0.01), (acc, 0.05), (mag, 0.3))]
    return noisy[0], noisy[1], noisy[2], 1.0 / rate_hz


def filter_cost() -> dict:
    """Instructions per 9D and 6D sample, on a whole BROAD trial (or a synthetic minute)."""
    try:
        trial = broad.load([ICOUNT_TRIAL])[0]
        recording = (trial.gyr, trial.acc, trial.mag, 1.0 / trial.rate_hz)
        name = f"BROAD {trial.name}"
    except DataMissingError:
        recording = _synthetic_recording()
        name = "synthetic, 60 s at 1 kHz"
    cost = qemu.filter_instructions_per_sample(*recording)
    return {"filter_instructions_per_sample_9d": round(cost["9d"], 1),
            "filter_instructions_per_sample_6d": round(cost["6d"], 1),
            "filter_instructions_resolution": round(cost["resolution"], 2),
            "filter_cost_recording": name}


def firmware() -> dict:
    """The benchmark line (one JSON object)."""
    result: dict = {"bench": "firmware", "board": PRODUCTION_BOARD, **image_size(), **filter_cost()}
    try:
        result["broad_rmse_deg"] = broad.figures()  # [total, heading, inclination] per group
    except DataMissingError as error:
        result["broad_rmse_deg"] = {"skipped": str(error)}
    return result
