"""Host tools of the mocap system: the C++ solver's bindings (mocap._core) and the Python
tools around it, in layered rooms that import only the rooms below them (CONTRIBUTING.md):
cli > demo > eval > takes > calibration | sim > recording | model > io > net | imu_node,
over errors, paths, rotations, processes, _core and the generated v1."""
