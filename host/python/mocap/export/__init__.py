"""The solver's outputs: BVH files, joint-position CSV and a live VMC (OSC over UDP) stream.

Each takes poses theta (the 66-D vector of mocap/skeleton.h) on a `mocap._core.Skeleton`.
"""

from mocap.export.bvh import write_bvh
from mocap.export.joints_csv import write_joints_csv
from mocap.export.vmc import VmcSender

__all__ = ["VmcSender", "write_bvh", "write_joints_csv"]
