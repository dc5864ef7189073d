"""The window calibration's check of its headings against the accelerometers'
(mocap.calibration.headings)."""

import dataclasses

import numpy as np

from mocap import rotations
from mocap.calibration import headings


@dataclasses.dataclass
class _Site:
    name: str
    reference: np.ndarray


@dataclasses.dataclass
class _Result:
    imus: list
    imu_residual_deg: list


def _site(name: str, yaw_deg: float) -> _Site:
    return _Site(name, rotations.exp(np.array([0.0, 0.0, np.radians(yaw_deg)])))


def _told(yaw_deg: float, sigma_deg: float) -> tuple[float, float]:
    return float(np.radians(yaw_deg)), float(np.radians(sigma_deg))


def _priors(accelerometer: dict, names: list[str]) -> list:
    return [np.array(accelerometer[n]) for n in names]


def test_headings_within_their_accelerometers_uncertainty_are_kept_without_a_second_solve():
    result = _Result([_site("shin", 3.4), _site("foot", 179.0)], [1.2, 0.6])
    told = {"shin": _told(6.0, 2.7), "foot": _told(-179.0, 3.0)}  # 2.6 deg; 2 deg across the wrap
    kept, held, left_out = headings.recheck(lambda priors: 1 / 0, result, told, _priors(told, ["shin", "foot"]))
    assert kept is result and held == {} and left_out == {}


def test_a_heading_its_accelerometer_contradicts_is_solved_again_held_there():
    result = _Result([_site("shin", 3.4), _site("foot", 113.5)], [1.2, 0.6])
    told = {"shin": _told(6.0, 2.7), "foot": _told(136.5, 3.2)}  # the foot 23 deg, 7 sigma off
    asked = []

    def solve(priors):
        asked.append(priors)
        return _Result([_site("shin", 3.3), _site("foot", 135.9)], [1.2, 0.8])

    kept, held, left_out = headings.recheck(solve, result, told, _priors(told, ["shin", "foot"]))
    assert len(asked) == 1 and kept is not result and left_out == {}
    np.testing.assert_allclose(asked[0][0], told["shin"])  # the others keep their priors
    np.testing.assert_allclose(asked[0][1], [np.radians(136.5), np.radians(headings.HOLD_SIGMA_DEG)])
    assert list(held) == ["foot"]
    assert abs(held["foot"]["window_deg"] - 113.5) < 1e-9 and abs(held["foot"]["heading_deg"] - 135.9) < 1e-9


def test_a_wide_accelerometer_uncertainty_tolerates_a_wider_disagreement():
    result = _Result([_site("pelvis", 116.0)], [0.9])
    assert headings.contradicted(result, {"pelvis": _told(66.0, 18.0)})  # 50 deg, 2.8 sigma
    assert not headings.contradicted(result, {"pelvis": _told(90.0, 18.0)})  # 26 deg, 1.4 sigma
    assert not headings.contradicted(result, {"pelvis": _told(66.0, float("inf"))})  # no accelerometer heading


def test_a_sensor_whose_orientations_fit_neither_heading_is_left_out_with_the_reason():
    result = _Result([_site("foot", 113.5)], [0.6])
    told = {"foot": _told(136.5, 3.2)}
    kept, held, left_out = headings.recheck(lambda priors: _Result([_site("foot", 136.0)], [4.0]), result, told,
                                            _priors(told, ["foot"]))
    assert list(left_out) == ["foot"] and "contradicts" in left_out["foot"] and "136" in left_out["foot"]
    assert held["foot"]["residual_deg_held"] == 4.0
