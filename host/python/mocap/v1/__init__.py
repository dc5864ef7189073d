"""The wire formats (package mocap.v1), generated from proto/mocap/v1/*.proto by
`make build` (protoc): import e.g. `from mocap.v1 import keypoint_frame_pb2`."""
