"""On-device keypoint detection: model-agnostic decoders (SSD boxes with keypoints,
heatmaps, SimCC, direct regression), rotated regions of interest, and the BlazePose
pipeline (person detector, landmark model) on onnxruntime."""
