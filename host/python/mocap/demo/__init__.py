"""The running system on one machine: a simulated studio played in real time by the edge
processes over ZeroMQ on loopback, mocapd solving live, the poses scored against the truth
(`mocap demo`, the live benchmark and the end-to-end tests)."""
