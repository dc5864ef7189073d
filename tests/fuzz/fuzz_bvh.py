"""atheris target: the BVH importer (mocap.io.bvh: the file read and parsed; mocap.io.retarget:
its joints mapped onto the solver's skeleton and its frames turned into poses). Input: the
file's bytes. Allowed failure: InputError."""

import atheris

with atheris.instrument_imports(include=["mocap.io"]):
    from mocap.errors import InputError
    from mocap.io import bvh, retarget

import _harness  # noqa: E402

PATH = _harness.scratch("mocap_fuzz_bvh_") / "clip.bvh"


def check(data: bytes) -> None:
    PATH.write_bytes(data)
    motion = bvh.load(PATH)
    assert motion.values.shape == (motion.num_frames, sum(len(j.channels) for j in motion.joints))
    mapping = retarget.map_joints(motion)
    retarget.poses(motion, mapping)


if __name__ == "__main__":
    _harness.main(check, (InputError,))
