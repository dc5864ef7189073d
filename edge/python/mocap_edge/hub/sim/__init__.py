"""Simulated sensor nodes: their clocks, their side of the CAN protocol, a whole bus in simulated
time, nodes on a real python-can bus in real time, and the simulated studio's IMUs as nodes."""
