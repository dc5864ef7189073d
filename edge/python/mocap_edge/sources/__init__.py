"""Frame sources of the camera box: one interface (`FrameSource`, an iterable of `Frame`s
with capture times on the shared timebase) and a registry of backends opened by URI:
video:PATH, images:DIR, v4l2:/dev/videoN, libcamera:N, fake:, sim:STREAMS (see base.py)."""

from mocap_edge.sources.base import BACKENDS, Frame, FrameSource, open_source

__all__ = ["BACKENDS", "Frame", "FrameSource", "open_source"]
