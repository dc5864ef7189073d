"""Each solver option is declared once, in C++ (SolverOptions::VisitFields), and reaches the
bindings, the session reader (what mocapd reads) and the Python wrapper (mocap.model.solver): this
fails when a field is missing from any of them."""

import json

import numpy as np
import pytest

from mocap import _core
from mocap.errors import InputError
from mocap.model import solver as wrapper


def _properties(cls) -> set[str]:
    return {name for name, value in vars(cls).items() if isinstance(value, property)}


def _flattened(cls, defaults) -> set[str]:
    """The option names the bindings export, a nested options struct's fields as a.b."""
    names = set()
    for name in _properties(cls):
        value = getattr(defaults, name)
        nested = type(value)
        names |= {f"{name}.{f}" for f in _properties(nested)} if hasattr(nested, "FIELDS") else {name}
    return names


@pytest.mark.parametrize("cls", [_core.TermOptions, _core.SolverOptions, _core.HeldPose, _core.CalibrationOptions])
def test_the_bindings_export_every_declared_field(cls):
    assert len(cls.FIELDS) == len(set(cls.FIELDS))
    assert _properties(cls) == set(cls.FIELDS)


def test_the_session_reader_and_the_wrapper_take_every_option_the_bindings_export():
    exported = _flattened(_core.SolverOptions, _core.SolverOptions())
    assert exported == set(_core.session_solver_keys()), "the session reader"
    assert exported == set(wrapper.option_names()), "the Python wrapper (mocap.model.solver)"
    assert len(exported) == 53  # 7 terms x 4 fields + 25 others: update when a field is added


def _changed(value):
    """A value of the option's type other than its default, still in range."""
    if isinstance(value, bool):
        return "false" if value else "true"
    if isinstance(value, _core.LossType):
        return "huber" if value != _core.LossType.HUBER else "cauchy"
    if isinstance(value, np.ndarray):
        return ",".join(str(v + 0.5) for v in value)
    if isinstance(value, float) and np.isnan(value):  # unknown (floor_height): a known value
        return "0.05"
    return str(value + 1) if isinstance(value, int) else str(value * 0.5 + 0.01)


def _get(options, name):
    target, _, field = name.rpartition(".")
    return getattr(getattr(options, target) if target else options, field)


def test_every_option_set_through_the_wrapper_is_what_the_session_reader_reads_back():
    defaults = _core.SolverOptions()
    names = wrapper.option_names()
    options = wrapper.solver_options([f"{n}={_changed(_get(defaults, n))}" for n in names])
    read = wrapper.options_from_session(json.loads(json.dumps(wrapper.session_solver(options))))
    for name in names:
        assert not np.array_equal(_get(options, name), _get(defaults, name)), name
        assert np.array_equal(_get(read, name), _get(options, name)), name


def test_unknown_or_malformed_options_are_refused_by_name():
    with pytest.raises(InputError, match="velocity_gian"):
        wrapper.solver_options(["velocity_gian=0.5"])
    with pytest.raises(InputError, match="position.loss"):
        wrapper.solver_options(["position.loss=cauchi"])
    with pytest.raises(InputError, match="max_iterations"):
        wrapper.solver_options(["max_iterations=2.5"])
    with pytest.raises(InputError, match=r"velocity_gain = 0 is out of range.*max_iterations = 0"):
        wrapper.solver_options(["velocity_gain=0", "max_iterations=0"])
    with pytest.raises(InputError, match="unknown key 'position.wieght'"):
        wrapper.options_from_session({"position": {"wieght": 1}})
    with pytest.raises(ValueError, match="num_threads = 0 is out of range"):
        options = _core.CalibrationOptions()
        options.num_threads = 0
        options.check()
