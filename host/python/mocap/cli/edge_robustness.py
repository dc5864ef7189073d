"""`python -m mocap.cli.edge_robustness [--seeds N]`: the edge detector's PCK on the real
trial in .cache/ (mocap.io.demo_data.fetch_trial), plain and under perturbations standing in
for other CPUs' rounding (mocap.eval.edge_detector.robustness), printed as JSON."""

from __future__ import annotations

import argparse
import json
import sys

from mocap.eval import edge_detector
from mocap.io.demo_data import fetch_trial


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mocap.cli.edge_robustness",
                                description="PCK of the edge detector on the real trial, plain and under "
                                "perturbations standing in for other CPUs' rounding")
    p.add_argument("--seeds", type=int, default=3, help="seeds per kind of noise (default 3)")
    args = p.parse_args(argv)
    print(json.dumps(edge_detector.robustness(fetch_trial(), seeds=args.seeds), indent=1), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
