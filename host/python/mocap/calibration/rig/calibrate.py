"""A rig's extrinsics from a take's detections of one person (the most confident in each
view), given each camera's intrinsics and the person's height."""

from __future__ import annotations

import json

import cv2
import numpy as np

from mocap import _core, paths
from mocap.calibration.rig import bundle, initial, views, world
from mocap.errors import InputError

MAX_FRAMES = 600  # frames used, evenly spread over the take (neighbours add little)


def _rig(intrinsics: list[_core.Camera], cams: bundle.Cameras) -> _core.Rig:
    out = []
    for given, r, t in zip(intrinsics, cams.rotation, cams.translation):
        cam = _core.Camera()
        for field in ("name", "width", "height", "fx", "fy", "cx", "cy", "distortion"):
            setattr(cam, field, getattr(given, field))
        cam.rotation, cam.translation = r, t
        out.append(cam)
    return _core.Rig(out)


def _report(obs: bundle.Observations, cams: bundle.Cameras, points: np.ndarray, names: list[str],
            place: world.World, frames: int) -> dict:
    r = np.linalg.norm(bundle.residuals(cams, points, obs)[0], axis=1)
    per_camera = {}
    for c, name in enumerate(names):
        mine = r[obs.camera == c]
        per_camera[name] = {"observations": int(len(mine)), "reprojection_px_median": float(np.median(mine)),
                            "reprojection_px_p90": float(np.percentile(mine, 90))}
    return {"frames": frames, "points": int(len(points)), "reprojection_px_median": float(np.median(r)),
            "cameras": per_camera, "up_from": place.up_from, "metres_per_unit": place.scale}


def keypoint_names(layout: str) -> list[str]:
    return [k["name"] for k in json.loads((paths.LAYOUTS / f"{layout}.json").read_text())["keypoints"]]


def calibrate(intrinsics: list[_core.Camera], people: list[list[np.ndarray]], layout: str, rate: float,
              height_m: float) -> tuple[_core.Rig, dict]:
    """The rig (the intrinsics' cameras with their estimated poses) and a report. people:
    per camera, per frame (P, K, 3) detections; layout: "coco17", "body25b" or "blazepose33"."""
    if not 0.5 <= height_m <= 2.5:
        raise InputError(f"a person {height_m} m tall: give the height in metres (0.5-2.5)")
    if len(people) != len(intrinsics):
        raise InputError(f"{len(people)} cameras' detections for {len(intrinsics)} cameras")
    names, layout = [c.name for c in intrinsics], keypoint_names(layout)
    if len({len(p) for p in people}) != 1:
        raise InputError("the cameras' detections differ in frames")
    step = -(-len(people[0]) // MAX_FRAMES)
    detections = [views.person_in_view(p[::step], len(layout)) for p in people]
    obs, keys = views.observations(intrinsics, detections)
    try:
        cams, points, fixed = initial.initial(obs, names)
        cams, points, _ = bundle.adjust(cams, points, obs, fixed=fixed)
    except (np.linalg.LinAlgError, cv2.error) as e:  # e.g. every point on one line, a camera at another's place
        raise InputError(f"the detections do not determine the cameras' poses ({e})") from None
    cams, points, place = world.place(cams, points, keys, layout, len(detections[0]), rate / step, height_m)
    return _rig(intrinsics, cams), _report(obs, cams, points, names, place, len(detections[0]))
