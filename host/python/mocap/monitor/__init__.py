"""The live view and status page (`mocap monitor`): a subscriber of mocapd's output that serves one
browser page — the solved skeleton in 3D, the cameras' frusta from the rig, each stream's health
and the host's latency — updated over a WebSocket as the poses arrive.

scene.py: what does not change during a take (bones, cameras), from the session's files;
messages.py: PoseFrame and Health as the page's JSON; server.py: the HTTP + WebSocket server;
web/: the page (three.js from npm, installed by `make setup`: no CDN at run time)."""
