"""The IMU sensor node's firmware seen from the host.

- :mod:`mocap.imu_node.filter`: the node's orientation filter (firmware/core/imu_filter.c),
  the same C built for this machine (libmocap_node.so), through ctypes.
- :mod:`mocap.imu_node.broad`: that filter, VQF and Fusion on the BROAD benchmark.
- :mod:`mocap.imu_node.qemu`: the firmware images run in qemu-system-arm.
"""
