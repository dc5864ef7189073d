"""The solver as the Python tools use it: with the shipped PCA prior unless told otherwise."""

from __future__ import annotations

import json

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.model import prior

_DEFAULT = object()


class Solver(_core.Solver):
    """`mocap._core.Solver` whose prior defaults to host/data/prior_default.json
    (`prior=None` solves without the prior terms)."""

    def __init__(self, skeleton, rig, layout, imus, prior_model=_DEFAULT, options=None):
        model = prior.load() if prior_model is _DEFAULT else prior_model
        super().__init__(skeleton, rig, layout, imus, model, options or _core.SolverOptions())


def distrust_spans(times, left_out: list[list[str]]) -> dict:
    """Of each sensor a solve left out on some frame (left_out: each frame's names, from
    SolveResult.imus_distrusted or PoseFrame.imus_distrusted at `times`, s): when first (s from
    the first frame) and for how long in all (s, its frames at the mean frame interval)."""
    times = np.asarray(times, dtype=float)
    step = float(np.mean(np.diff(times))) if len(times) > 1 else 0.0
    out: dict = {}
    start = times[0] if len(times) else 0.0
    for time, names in zip(times - start, left_out):
        for name in names:
            span = out.setdefault(name, {"first_s": float(time), "seconds": 0.0})
            span["seconds"] += step
    return out


def imu_set_json(skeleton: _core.Skeleton, imus) -> dict:
    """IMU sites in the solver's IMU set format (mocap.imus/1, sites.h)."""
    return json.loads(_core.imu_sites_to_json(skeleton, list(imus)))


def layout_json(skeleton: _core.Skeleton, layout: _core.KeypointLayout) -> dict:
    """A keypoint layout in the layout file format (mocap.layout/1, sites.h), its offsets as
    they are for `skeleton` (reference_height = its rest height: loading scales by 1)."""
    return json.loads(_core.layout_to_json(skeleton, layout))


# Options: the fields are those the C++ structs declare (SolverOptions.FIELDS, from
# SolverOptions::VisitFields); a setting is parsed by the type of the field's default.
def _parse_bool(value: str, current: bool) -> bool:
    if value.lower() not in ("1", "true", "on", "0", "false", "off"):
        raise ValueError(f"{value!r} is not true or false")
    return value.lower() in ("1", "true", "on")


def _parse_int(value: str, current: int) -> int:
    number = float(value)
    if number != int(number):
        raise ValueError(f"{value!r} is not an integer")
    return int(number)


def _parse_loss(value: str, current: _core.LossType) -> _core.LossType:
    names = _core.LossType.__members__
    if value.upper() not in names:
        raise ValueError(f"{value!r} is not one of {', '.join(n.lower() for n in names)}")
    return names[value.upper()]


def _parse_vector(value: str, current: np.ndarray) -> np.ndarray:
    vector = np.array([float(v) for v in value.split(",")])
    if vector.shape != np.shape(current):
        raise ValueError(f"{value!r} is not {len(current)} comma-separated numbers")
    return vector


_PARSERS = {bool: _parse_bool, int: _parse_int, float: lambda value, current: float(value),
            _core.LossType: _parse_loss, np.ndarray: _parse_vector}


def option_names() -> list[str]:
    """Every setting solver_options takes: each SolverOptions field, a term's fields as
    "term.field" (the session file's keys, _core.session_solver_keys(), the same)."""
    defaults, names = _core.SolverOptions(), []
    for name in _core.SolverOptions.FIELDS:
        value = getattr(defaults, name)
        fields = _core.TermOptions.FIELDS if isinstance(value, _core.TermOptions) else [None]
        for field in fields:
            current = getattr(value, field) if field else value
            if type(current) in _PARSERS:
                names.append(f"{name}.{field}" if field else name)
    return names


def solver_options(settings: list[str], base: _core.SolverOptions | None = None) -> _core.SolverOptions:
    """SolverOptions (`base`, changed in place, or the defaults) with "name=value" or
    "term.field=value" settings applied (option_names(); a loss by name, a vector as
    comma-separated numbers). InputError names a setting that is unknown, has no value or does
    not parse, and every field out of range."""
    options, known = base if base is not None else _core.SolverOptions(), option_names()
    for setting in settings:
        name, _, value = setting.partition("=")
        if name not in known or not value:
            raise InputError(f"unknown solver option or missing value: {setting!r} (known: {', '.join(known)})")
        target, _, field = name.rpartition(".")
        owner = getattr(options, target) if target else options
        current = getattr(owner, field)
        try:
            setattr(owner, field, _PARSERS[type(current)](value, current))
        except ValueError as e:
            raise InputError(f"solver option {setting!r}: {e}") from None
        if target:
            setattr(options, target, owner)  # terms are copied out and back
    try:
        options.check()
    except ValueError as e:
        raise InputError(f"solver options: {e}") from None
    return options


def session_solver(options: _core.SolverOptions) -> dict:
    """The session file's "solver" object of these options: every field, as mocapd reads it."""
    return json.loads(options.to_session_json())


def options_from_session(solver: dict) -> _core.SolverOptions:
    """Options from a session's "solver" object, read as mocapd reads it (InputError naming
    an unknown key, a value of the wrong type or a field out of range)."""
    try:
        return _core.SolverOptions.from_session_json(json.dumps(solver))
    except ValueError as e:
        raise InputError(str(e)) from None
