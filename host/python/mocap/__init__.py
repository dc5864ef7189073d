"""Host tools of the mocap system: the C++ solver's bindings (mocap._core) and the
Python tools around it (BVH, retargeting, prior, benchmarks, command line)."""
