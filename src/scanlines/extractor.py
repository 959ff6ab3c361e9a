"""The one entry point: a configured :class:`Extractor`, and :func:`extract`."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from scanlines.errors import ScanError
from scanlines.extraction import Extraction
from scanlines.methods import REGISTRY, method_class
from scanlines.params import resolve
from scanlines.scan import Scan, valid_returns

__all__ = ["Extractor", "extract", "method_info", "method_names"]


def method_names() -> tuple[str, ...]:
    """Names of the registered methods."""
    return tuple(REGISTRY)


def method_info(method: str) -> dict[str, Any]:
    """Parameters (default and doc) and presets of ``method``."""
    cls = method_class(method)
    module = sys.modules[cls.__module__]
    return {
        "name": cls.name,
        "doc": (module.__doc__ or cls.__doc__ or "").strip().splitlines()[0],
        "params": {name: (p.default, p.doc) for name, p in cls.parameters.items()},
        "presets": {name: dict(values) for name, values in cls.presets.items()},
    }


class Extractor:
    """A configured extractor; call it on a :class:`~scanlines.Scan`.

    Parameters
    ----------
    method:
        A name from :func:`method_names`; ``"adaptive"`` is the paper's method.
    preset:
        A named parameter set of the method (``"paper"``: the paper, literally).
    **params:
        Overrides of single parameters (see :func:`method_info`).

    Raises
    ------
    ParameterError
        For an unknown method, preset or parameter (the message lists the valid
        ones) or a value out of range.

    Notes
    -----
    Bearing tables are cached per sensor (beam count and increment), so one
    extractor reused over a log does not recompute them.
    """

    def __init__(self, method: str = "adaptive", preset: str | None = None, **params: Any) -> None:
        cls = method_class(method)
        self.method = method
        self.preset = preset
        self.params: Mapping[str, Any] = MappingProxyType(
            resolve(method, cls.parameters, cls.presets, preset, params)
        )
        self._tables: dict[tuple[int, float], tuple[np.ndarray, np.ndarray]] = {}
        self._method = cls(self.params)

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild_extractor, (self.method, self.preset, dict(self.params))

    def __repr__(self) -> str:
        preset = f", preset={self.preset!r}" if self.preset else ""
        return f"Extractor(method={self.method!r}{preset})"

    def __call__(self, scan: Scan) -> Extraction:
        """Extract segments, breakpoints and corners of ``scan``."""
        if not isinstance(scan, Scan):
            raise ScanError(f"expected a scanlines.Scan, got {type(scan).__name__}")
        cos, sin = self._bearings(len(scan), scan.angle_increment)
        return self._method.extract(
            scan.ranges, scan.valid, cos, sin, scan.angle_increment, scan.angle_min
        )

    def batch(
        self,
        ranges: np.ndarray,
        angle_min: float,
        angle_increment: float,
        range_min: float = 0.0,
        range_max: float = math.inf,
    ) -> list[Extraction]:
        """Extract from a stack of scans of one sensor, ``ranges`` of shape (scans, beams).

        Gives exactly what calling the extractor on each row as a :class:`Scan` gives,
        without building the scans: the stack is validated once, the validity
        mask computed for all rows at once and the bearing tables shared.
        """
        # Validate the sensor fields once, as Scan does (same errors).
        sensor = Scan(np.zeros(0), angle_min, angle_increment, range_min, range_max)
        stack = np.asarray(ranges)
        if stack.ndim != 2:
            raise ScanError(f"ranges must be 2-D (scans, beams), got shape {stack.shape}")
        if stack.dtype.kind not in "fiu" or stack.dtype == np.bool_:
            raise ScanError(f"ranges must hold real numbers, got dtype {stack.dtype}")
        stack = stack.astype(np.float64, copy=False)
        valid = valid_returns(stack, sensor.range_min, sensor.range_max)
        step = sensor.angle_increment
        cos, sin = self._bearings(stack.shape[1], step)
        stack = np.ascontiguousarray(stack)
        return self._method.extract_many(stack, valid, cos, sin, step, sensor.angle_min)

    def _bearings(self, n_beams: int, increment: float) -> tuple[np.ndarray, np.ndarray]:
        key = (n_beams, increment)
        table = self._tables.get(key)
        if table is None:
            local = increment * np.arange(n_beams, dtype=np.float64)
            table = (np.cos(local), np.sin(local))
            if len(self._tables) > 16:
                self._tables.clear()
            self._tables[key] = table
        return table


def _rebuild_extractor(method: str, preset: str | None, params: dict[str, Any]) -> Extractor:
    return Extractor(method, preset, **params)


def extract(
    scan: Scan, method: str = "adaptive", preset: str | None = None, **params: Any
) -> Extraction:
    """One-shot form of :class:`Extractor`: ``Extractor(method, preset, **params)(scan)``."""
    return Extractor(method, preset, **params)(scan)
