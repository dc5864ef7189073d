"""One filter, two targets: the orientation filter built for the Cortex-M4F (QEMU's
mps2-an386, firmware/boards/mps2_an386) gives the host build's quaternions."""

from __future__ import annotations

import numpy as np
import pytest

from mocap.imu_node import filter as host_filter

TOLERANCE = 1e-5
SECONDS = 5.0
BROAD_TRIALS = ["01_undisturbed_slow_rotation_A", "29_disturbed_stationary_magnet_B"]


def synthetic_recording(seconds: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A sensor turning about a wobbling axis, gravity and a 50 uT field rotated into it, noise."""
    rng = np.random.default_rng(7)
    n = int(seconds * rate_hz)
    t = np.arange(n) / rate_hz
    gyr = np.stack([0.8 * np.sin(1.3 * t), 0.5 * np.cos(0.7 * t), 1.5 * np.sin(0.4 * t)], axis=1)
    angle = np.cumsum(gyr, axis=0) / rate_hz  # small-angle stand-in for the attitude
    acc = np.stack([9.81 * np.sin(angle[:, 1]), -9.81 * np.sin(angle[:, 0]), 9.81 * np.cos(angle[:, 0])], axis=1)
    mag = np.stack([20 * np.cos(angle[:, 2]), -20 * np.sin(angle[:, 2]), -45 + 0 * t], axis=1)
    noisy = [(x + rng.normal(0, s, x.shape)).astype(np.float32) for x, s in ((gyr, 0.01), (acc, 0.05), (mag, 0.3))]
    return noisy[0], noisy[1], noisy[2], 1.0 / rate_hz


def assert_same_quaternions(qemu_arm, gyr, acc, mag, period):
    # Test: the same samples through the firmware in QEMU and through the host library.
    run = qemu_arm.run_filter(gyr, acc, mag, period)
    host = host_filter.run(gyr, acc, mag, period)
    # Assert: every quaternion within TOLERANCE, and the cost measurement is sound
    # (-icount shift=0: one instruction per ns; SysTick at 25 MHz: 40 instructions a tick).
    assert run.quaternions.shape == host.quaternions.shape
    assert np.all(np.isfinite(run.quaternions))
    np.testing.assert_allclose(run.quaternions, host.quaternions, rtol=0, atol=TOLERANCE)
    assert run.instructions_per_tick == pytest.approx(40.0)
    assert run.instructions_per_sample > 0


@pytest.mark.parametrize("use_mag", [True, False], ids=["9d", "6d"])
def test_filter_in_qemu_equals_host_on_a_synthetic_recording(qemu_arm, use_mag):
    # Fixture: 5 s of a synthetic recording at 400 Hz.
    gyr, acc, mag, period = synthetic_recording(SECONDS, 400.0)
    assert_same_quaternions(qemu_arm, gyr, acc, mag if use_mag else None, period)


@pytest.mark.parametrize("trial", BROAD_TRIALS)
@pytest.mark.parametrize("use_mag", [True, False], ids=["9d", "6d"])
def test_filter_in_qemu_equals_host_on_broad(qemu_arm, shared, trial, use_mag):
    # Fixture: the first 5 s of a BROAD trial (real sensor data).
    path = shared / "data" / "imu" / "broad" / f"{trial}.npz"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    data = np.load(path)
    n = int(SECONDS * float(data["rate"]))
    mag = data["mag"][:n] if use_mag else None
    assert_same_quaternions(qemu_arm, data["gyr"][:n], data["acc"][:n], mag, 1.0 / float(data["rate"]))
