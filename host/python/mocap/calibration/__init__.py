"""Calibration without oracles: the subject's skeleton, the keypoint sites and each IMU's
mounting, heading and position estimated from a few seconds of the take itself — from
arrays (`window`, `informative`), from the streams' messages (`from_messages`), from a
recording (`from_recording`) or live beside mocapd (`live`)."""
