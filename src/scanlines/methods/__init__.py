"""Extractors, one module each, and the registry that names them.

Every method is a :class:`~scanlines.methods.base.Method` subclass (see
:mod:`scanlines.methods.base` for the protocol). :data:`REGISTRY` maps names to
classes in listing order; :func:`register` adds a method of your own, after which
``Extractor("name")``, ``extract``, ``scanlines eval -m name`` and the writers take
it like a built-in one (``docs/ARCHITECTURE.md`` walks through it).
"""

from __future__ import annotations

from scanlines.errors import ParameterError
from scanlines.methods.adaptive import Adaptive
from scanlines.methods.base import ClusteredMethod, CompiledMethod, Method
from scanlines.methods.hough import Hough
from scanlines.methods.iepf import Iepf
from scanlines.methods.line_regression import LineRegression
from scanlines.methods.line_tracking import LineTracking
from scanlines.methods.paper import Paper
from scanlines.methods.partition import Partition
from scanlines.methods.pdbs import Pdbs
from scanlines.methods.ransac import Ransac
from scanlines.methods.split_merge import SplitMerge
from scanlines.methods.surfaces import Surfaces
from scanlines.untrusted import quote

__all__ = [
    "REGISTRY",
    "ClusteredMethod",
    "CompiledMethod",
    "Method",
    "method_class",
    "register",
    "unregister",
]

REGISTRY: dict[str, type[Method]] = {
    method.name: method
    for method in (
        Adaptive,
        Paper,
        Iepf,
        Pdbs,
        SplitMerge,
        LineTracking,
        LineRegression,
        Ransac,
        Hough,
        Partition,
        Surfaces,
    )
}


def register(method: type[Method]) -> type[Method]:
    """Add ``method`` (a :class:`Method` subclass) to the registry under its ``name``.

    Returns the class, so it can be used as a decorator. A name already taken
    raises :class:`~scanlines.ParameterError` (:func:`unregister` it first).
    """
    if not (isinstance(method, type) and issubclass(method, Method)) or not method.name:
        raise ParameterError(f"register takes a named Method subclass, got {method!r}")
    if method.name in REGISTRY:
        raise ParameterError(f"a method named {method.name!r} is registered already")
    REGISTRY[method.name] = method
    return method


def unregister(name: str) -> None:
    """Remove the method ``name`` from the registry (unknown names are ignored)."""
    REGISTRY.pop(name, None)


def method_class(name: str) -> type[Method]:
    """The class registered as ``name``; an unknown name lists the valid ones."""
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        valid = ", ".join(REGISTRY)
        raise ParameterError(f"unknown method {quote(name)}; valid: {valid}") from None
