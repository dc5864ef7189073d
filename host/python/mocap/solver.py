"""The solver as the Python tools use it: with the shipped PCA prior unless told otherwise."""

from __future__ import annotations

from mocap import _core, prior

_DEFAULT = object()


class Solver(_core.Solver):
    """`mocap._core.Solver` whose prior defaults to host/data/prior_default.json
    (`prior=None` solves without the prior terms)."""

    def __init__(self, skeleton, rig, layout, imus, prior_model=_DEFAULT, options=None):
        model = prior.load() if prior_model is _DEFAULT else prior_model
        super().__init__(skeleton, rig, layout, imus, model, options or _core.SolverOptions())
