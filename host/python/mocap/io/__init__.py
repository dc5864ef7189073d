"""Files the system reads and writes: BVH (reading, retargeting onto the solver's skeleton,
writing), Calib.toml rigs, Xsens CSV, take folders, TRC markers, joint CSV, the session
file, and the registry data the demo uses. Each reader checks its input and names the
file, line and column of a fault (mocap.errors.InputError, TakeError)."""
