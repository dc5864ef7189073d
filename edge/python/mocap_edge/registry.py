"""Registries of backends, one per device kind (frame sources, keypoint models): a backend
is named by a URI `name:location` and listed as "module:attribute", imported only when
opened, so a box needs only its own backend's modules (python-can's interface registry).
The attribute is called as `attribute(location, **options)`; options it does not take are
reported as the kind's error, not as a TypeError from deep inside the backend."""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable, Mapping
from typing import Any

from mocap_edge.errors import EdgeError


def known(backends: Mapping[str, str]) -> str:
    return ", ".join(f"{name}:" for name in backends)


def factory(backends: Mapping[str, str], name: str) -> Callable[..., Any]:
    """The backend's constructor (a class or a function), imported now."""
    module_name, _, attribute = backends[name].partition(":")
    return getattr(importlib.import_module(module_name), attribute)


def open_backend(backends: Mapping[str, str], uri: str, error: type[EdgeError], kind: str,
                 **options: object) -> Any:
    """The backend named by `uri` (`name:location`, or a bare `name`) built with `options`;
    raises `error` for an unknown name or options the backend does not take."""
    name, _, location = uri.partition(":")
    if name not in backends:
        raise error(f"unknown {kind} {uri!r}: the name must be one of {known(backends)}")
    build = factory(backends, name)
    try:
        inspect.signature(build).bind(location, **options)
    except TypeError as e:
        raise error(f"{name}: {kind} options: {e}") from None
    return build(location, **options)
