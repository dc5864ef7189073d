"""The edge boxes: camera nodes and the IMU hub, publishing mocap.v1 messages over
ZeroMQ (mocap.wire, mocap.transport). Devices sit behind adapters; until hardware is
attached the sources are the simulated studio's streams (streams.py)."""
