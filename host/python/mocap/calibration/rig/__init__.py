"""Camera calibration without a board: the cameras' poses from the people in view
(`mocap calibrate-rig`). views: the detections as normalised observations; initial: the first
poses (essential matrix, PnP); bundle: the bundle adjustment; world: metres, up and origin;
calibrate: the whole."""
