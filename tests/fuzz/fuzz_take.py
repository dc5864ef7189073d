"""atheris target: the take-folder readers (mocap.io.take_folder, calib_toml, xsens_csv): take.toml,
Calib.toml, the OpenPose JSON of each frame, sensors.csv and each Xsens CSV. Input:
[selector][bytes]: selector % (number of files) picks which file of the fixture take
(tests/fuzz/take/: 2 cameras, 3 frames, 2 IMUs) the bytes replace, the others stay valid.
Allowed failure: TakeError, naming the file."""

import shutil
from pathlib import Path

import atheris

with atheris.instrument_imports(include=["mocap.io"]):
    from mocap.errors import TakeError
    from mocap.io import take_folder

import _harness  # noqa: E402

FIXTURE = Path(__file__).resolve().parent / "take"
FOLDER = _harness.Folder(lambda d: shutil.copytree(FIXTURE, d, dirs_exist_ok=True))
FILES = FOLDER.files


def check(data: bytes) -> None:
    if not data:
        return
    name = FILES[data[0] % len(FILES)]
    with FOLDER.replaced(name, bytes(data[1:])) as folder:
        try:
            take = take_folder.read_take(folder)
        except TakeError as e:
            assert e.path.is_relative_to(folder), e  # names a file of the take
            raise
    assert take.n_frames == len(take.people[0]) if take.people else True


if __name__ == "__main__":
    _harness.main(check, (TakeError,))
