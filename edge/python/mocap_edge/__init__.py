"""The edge boxes: camera boxes and the IMU hub, publishing mocap.v1 messages over
ZeroMQ (mocap.net.wire, mocap.net.transport: the only part of the host package the edge
imports). Devices sit behind one base class per kind with a registry of backends and an
in-process fake; the simulated studio is a backend of the camera box like any other
(`sim:`, streams.py), and the IMU hub still plays its streams."""
