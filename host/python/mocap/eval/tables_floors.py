"""docs/results.md's per-bone table: the 13 IMU HQ solve's orientation error beside what the
measurements themselves allow (mocap.eval.floors), over the test clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap.eval import floors
from mocap.sim import take


def compute(clips: list[Path], seed: int) -> list[dict]:
    return [floors.evaluate(c, take.Config(preset="hq13"), seed) for c in clips]


def _mean(values) -> float:
    return float(np.nanmean(list(values)))


def markdown(r: dict) -> list[str]:
    solved = r["configurations"]["hq13"]["clips"]
    fl = r["floors"]
    bones = list(solved[0]["per_joint"])
    lines = ["## Per bone: the solve against what its measurements allow (13 IMU, HQ)", "",
             "Mean over the test clips, degrees (`mocap.eval.floors`; one clip: `mocap eval --floors --motion CLIP "
             "--json F`). Sensor: its reading's own error (spec error, drift, soft-tissue wobble). Floor: the "
             "bone's orientation fitted to one frame's detections of the keypoints it moves, everything else at "
             "the truth, with the layout's nominal keypoint sites (as this solve knows them) and with the "
             "detector's true sites (a calibration that found them exactly); a direction no keypoint observes "
             "(a toe's roll, a neck's twist) is left at the truth; frames with fewer than three detections of the "
             "keypoints it moves are left out (their share in the last column). 131 clips: the three held-out dance clips.", "",
             "| bone | solve | solve, 131 clips | sensor | floor, nominal sites | floor, true sites | frames left out |",
             "|---|---|---|---|---|---|---|"]
    dance = [i for i, c in enumerate(solved) if Path(c["clip"]).stem.startswith("131")]
    for b in bones:
        solve = _mean(c["per_joint"][b]["ori_deg"] for c in solved)
        solve_131 = _mean(solved[i]["per_joint"][b]["ori_deg"] for i in dance) if dance else np.nan
        if b in fl[0]["sensors_deg"]:
            cells = [f"{_mean(f['sensors_deg'][b] for f in fl):.1f}", "", "", ""]
        else:
            cells = ["", *(f"{_mean(f['floors'][b][k] for f in fl):.1f}" for k in ("floor_deg", "floor_true_sites_deg")),
                     f"{_mean(f['floors'][b]['unobserved_pct'] for f in fl):.0f}%"]
        lines.append(f"| {b} | {solve:.1f} | {solve_131:.1f} | " + " | ".join(cells) + " |")

    def allowed(key: str) -> float:  # each bone its sensor's error or its floor, averaged over bones
        return float(np.mean([_mean(f["sensors_deg"].get(b, f["floors"].get(b, {}).get(key)) for f in fl)
                              for b in bones]))

    lines += ["", f"The 21-bone mean of these figures (each bone its sensor's error or its floor): "
                  f"{allowed('floor_deg'):.1f} deg with nominal sites, {allowed('floor_true_sites_deg'):.1f} with "
                  "true sites. A solve beats them where another measurement or the prior knows more (the keypoints "
                  "correct a sensor's wobble; the prior knows the cmu-daz clips' toes, held at zero there)."]
    return lines
