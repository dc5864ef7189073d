"""Fixtures of the QEMU tests: they skip when qemu-system-arm is not installed."""

from __future__ import annotations

import pytest

from mocap import paths
from mocap.imu_node import qemu


@pytest.fixture
def qemu_arm():
    """The qemu module, when qemu-system-arm is installed (else the test skips)."""
    if not qemu.qemu_available():
        pytest.skip(f"{qemu.QEMU_BINARY} is not installed")
    return qemu


@pytest.fixture
def shared():
    """The ../shared data folder; tests that need it skip with a message when it is absent."""
    root = paths.shared_dir()
    if not root.is_dir():
        pytest.skip(f"development data not present at {root} (../shared is for development and CI only)")
    return root
