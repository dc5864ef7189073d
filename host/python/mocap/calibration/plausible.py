"""Mountings the window's own evidence refuses (mocap.calibration.window, step 4).

The window calibration solves each IMU's mounting together with the window's poses, from a
start fitted to a video-only solve (step 3). Where video barely sees a bone's twist (a foot
without heel and toe keypoints, a forearm without hand keypoints) a start half a turn off can
end in a local minimum that fits the sensor's orientations just as well: the bone held
upside down for the whole window, a foot rolled 160-180 degrees about its long axis while its
ankle stays where the keypoints put it. The pose prior says so: such a bone sits far from
anything the training motion holds. A sensor whose bone's median turn from the prior's mean
pose over the window exceeds IMPLAUSIBLE_DEG is solved again from its mounting turned half
a turn about each of its bone's axes; the plausible solution of lowest window cost is kept,
and when none is plausible the sensor is left out, with the reason in the report. A
performer who holds a joint that far out for the whole window (arms overhead) only costs
the three extra solves: the first solution stays when no other is plausible and cheaper.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mocap import _core, rotations

# deg: on the test clips a sensor bone's median turn from the prior's mean over a window is
# 8-42 degrees (with the true calibration's poses up to 88 at the peak); a foot whose mounting
# came out half a turn off, 168.
IMPLAUSIBLE_DEG = 120.0
_HALF_TURNS = {axis: rotations.exp(np.pi * np.eye(3)[i]) for i, axis in enumerate("xyz")}


def turn_from_mean_deg(thetas: np.ndarray, bone: int, prior_mean: np.ndarray) -> np.ndarray:
    """(W,) degrees between the bone's joint rotation in each pose (W, 66) and the prior's mean
    (the prior's DOF are the joints', bone 1 first)."""
    mean = rotations.exp(prior_mean[3 * (bone - 1): 3 * bone])
    joint = rotations.exp(thetas[:, 3 + 3 * bone: 6 + 3 * bone])
    return np.degrees(rotations.angle_between(mean[None], joint))


def median_turn_deg(thetas: np.ndarray, bone: int, prior_mean: np.ndarray) -> float:
    """The median of turn_from_mean_deg; 0 for the root, which has no joint."""
    return float(np.median(turn_from_mean_deg(thetas, bone, prior_mean))) if bone > 0 else 0.0


def _turned(site: _core.ImuSite, half: np.ndarray) -> _core.ImuSite:
    """A copy of the site whose mounting holds its bone turned by `half` in the bone's frame."""
    out = _core.ImuSite()
    out.name, out.bone, out.offset, out.reference = site.name, site.bone, site.offset, site.reference
    out.mount = half @ np.asarray(site.mount)
    return out


def recheck(solve: Callable[[list], object], result, prior_mean: np.ndarray) -> tuple[object, dict, dict]:
    """The window solution (result: a calibrate_window result) with every implausible mounting
    solved again (solve(sites) -> a result, from those IMU sites): (the solution kept, what was
    done per sensor rechecked, the sensors left out -> why)."""
    rechecked, left_out = {}, {}
    for i, site in enumerate(list(result.imus)):
        turn = median_turn_deg(np.asarray(result.thetas), site.bone, prior_mean)
        if turn <= IMPLAUSIBLE_DEG:
            continue
        tries = {}
        for axis, half in _HALF_TURNS.items():
            sites = list(result.imus)
            sites[i] = _turned(sites[i], half)
            r = solve(sites)
            tries[axis] = (median_turn_deg(np.asarray(r.thetas), site.bone, prior_mean), r)
        plausible = {a: t for a, t in tries.items() if t[0] <= IMPLAUSIBLE_DEG}
        rechecked[site.name] = {"turn_deg": turn, "tries": {a: {"turn_deg": t, "cost": r.final_cost}
                                                            for a, (t, r) in tries.items()}}
        if plausible:
            axis = min(plausible, key=lambda a: plausible[a][1].final_cost)
            result = plausible[axis][1]
            rechecked[site.name]["kept"] = f"half a turn about {axis}"
        else:
            left_out[site.name] = (f"its bone stays {turn:.0f} deg from the prior's mean pose over the window "
                                   "with every mounting tried: an implausible pose the window cannot explain")
    return result, rechecked, left_out
