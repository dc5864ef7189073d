"""`mocap detect VIDEO --out DIR`: the edge keypoint detector on a video, OpenPose-style JSON."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap_edge.detect.video import detect_video


def register(sub: argparse._SubParsersAction) -> None:
    de = sub.add_parser("detect", help="the edge keypoint detector (BlazePose, region tracking) on a video: "
                        "one OpenPose-style JSON per frame")
    de.add_argument("video", help="video file")
    de.add_argument("--out", required=True, help="folder of the JSON files")
    de.add_argument("--max-people", type=int, default=2, help="people tracked at once (default 2)")
    de.add_argument("--model", default="blazepose", help="blazepose (default) or a model configuration JSON "
                    "(edge/python/mocap_edge/detect/topdown.py)")
    de.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(json.dumps(detect_video(Path(args.video), Path(args.out), max_people=args.max_people, model=args.model)),
          flush=True)
    return 0
