"""What crosses the network: the mocap.v1 wire framing (`wire`), ZeroMQ PUB/SUB as every
process uses it (`transport`) and the live VMC (OSC over UDP) output (`vmc`).

The lowest room of the host, and the only one the edge boxes (`mocap_edge`) import: it
imports nothing of the host but the generated messages (`mocap.v1`) and the rotations.
"""
