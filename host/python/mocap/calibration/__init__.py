"""Calibration without oracles (issue 6): the subject's skeleton, and later the IMUs'
mounting, heading and position, estimated from the take itself."""
