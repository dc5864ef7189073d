"""The solver as the Python tools use it: with the shipped PCA prior unless told otherwise."""

from __future__ import annotations

import json


from mocap import _core, prior
from mocap.errors import InputError

_DEFAULT = object()


class Solver(_core.Solver):
    """`mocap._core.Solver` whose prior defaults to host/data/prior_default.json
    (`prior=None` solves without the prior terms)."""

    def __init__(self, skeleton, rig, layout, imus, prior_model=_DEFAULT, options=None):
        model = prior.load() if prior_model is _DEFAULT else prior_model
        super().__init__(skeleton, rig, layout, imus, model, options or _core.SolverOptions())


def imu_set_json(skeleton: _core.Skeleton, imus) -> dict:
    """IMU sites in the solver's IMU set format (mocap.imus/1, sites.h)."""
    return json.loads(_core.imu_sites_to_json(skeleton, list(imus)))


def layout_json(skeleton: _core.Skeleton, layout: _core.KeypointLayout) -> dict:
    """A keypoint layout in the layout file format (mocap.layout/1, sites.h), its offsets as
    they are for `skeleton` (reference_height = its rest height: loading scales by 1)."""
    return json.loads(_core.layout_to_json(skeleton, layout))


def solver_options(settings: list[str]) -> _core.SolverOptions:
    """SolverOptions with "name=value" or "term.field=value" settings applied."""
    options = _core.SolverOptions()
    for setting in settings:
        name, _, value = setting.partition("=")
        target, _, field = name.rpartition(".")
        owner = getattr(options, target) if target else options
        if not hasattr(owner, field) or not value:
            raise InputError(f"unknown solver option or missing value: {setting!r}")
        current = getattr(owner, field)
        setattr(owner, field, value.lower() in ("1", "true", "on") if isinstance(current, bool) else type(current)(float(value)))
        if target:
            setattr(options, target, owner)  # terms are copied out and back
    return options
