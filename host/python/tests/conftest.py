import pytest

from mocap import paths


@pytest.fixture
def shared():
    """The ../shared data folder; tests that need it skip with a message when it is absent."""
    root = paths.shared_dir()
    if not (root / "data").is_dir():
        pytest.skip(f"development data not present at {root} (../shared is for development and CI only)")
    return root
