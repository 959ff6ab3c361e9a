"""The one entry point: a configured :class:`Extractor`, and :func:`extract`."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from scanlines.errors import ScanError
from scanlines.extraction import Extraction
from scanlines.methods import REGISTRY, method_class
from scanlines.params import resolve
from scanlines.scan import Scan, valid_returns
from scanlines.sensor_profile import SensorProfile, as_profile

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
    sensor_profile:
        A :class:`~scanlines.sensor_profile.SensorProfile` (or the path of one saved
        by ``scanlines calibrate``): the range noise every threshold and covariance
        takes. Without one, each scan's noise is measured from that scan alone.
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

    Ranges and angles are taken at float32 precision (that of
    ``sensor_msgs/LaserScan``, about 5 um at 80 m): a log gives the same features
    whether it was read from its own file or from a ROS bag it was copied into.
    """

    def __init__(
        self,
        method: str = "adaptive",
        preset: str | None = None,
        *,
        sensor_profile: SensorProfile | str | Path | None = None,
        **params: Any,
    ) -> None:
        cls = method_class(method)
        self.method = method
        self.preset = preset
        self.sensor_profile = as_profile(sensor_profile)
        self.params: Mapping[str, Any] = MappingProxyType(
            resolve(method, cls.parameters, cls.presets, preset, params)
        )
        self._tables: dict[tuple[int, float], tuple[np.ndarray, np.ndarray]] = {}
        noise = None if self.sensor_profile is None else self.sensor_profile.noise
        self._method = cls(self.params, noise)

    def __reduce__(self) -> tuple[Any, ...]:
        rebuild = (self.method, self.preset, dict(self.params), self.sensor_profile)
        return _rebuild_extractor, rebuild

    def __repr__(self) -> str:
        preset = f", preset={self.preset!r}" if self.preset else ""
        return f"Extractor(method={self.method!r}{preset})"

    def __call__(self, scan: Scan) -> Extraction:
        """Extract segments, breakpoints and corners of ``scan``."""
        if not isinstance(scan, Scan):
            raise ScanError(f"expected a scanlines.Scan, got {type(scan).__name__}")
        ranges = at_float32(scan.ranges)
        step, angle_min = float32(scan.angle_increment), float32(scan.angle_min)
        valid = valid_returns(ranges, float32(scan.range_min), float32(scan.range_max))
        cos, sin = self._bearings(len(scan), step)
        return self._method.extract(ranges, valid, cos, sin, step, angle_min)

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
        stack = at_float32(stack)
        valid = valid_returns(stack, float32(sensor.range_min), float32(sensor.range_max))
        step, angle_min = float32(sensor.angle_increment), float32(sensor.angle_min)
        cos, sin = self._bearings(stack.shape[1], step)
        return self._method.extract_many(stack, valid, cos, sin, step, angle_min)

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


def float32(value: float) -> float:
    """``value`` rounded to float32 precision (infinities stay)."""
    return float(np.float32(value))


def at_float32(ranges: np.ndarray) -> np.ndarray:
    """Ranges rounded to float32 precision, as a C-contiguous float64 array."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.ascontiguousarray(np.asarray(ranges).astype(np.float32), dtype=np.float64)


def _rebuild_extractor(
    method: str, preset: str | None, params: dict[str, Any], profile: SensorProfile | None = None
) -> Extractor:
    return Extractor(method, preset, sensor_profile=profile, **params)


def extract(
    scan: Scan,
    method: str = "adaptive",
    preset: str | None = None,
    *,
    sensor_profile: SensorProfile | str | Path | None = None,
    **params: Any,
) -> Extraction:
    """One-shot form of :class:`Extractor`:
    ``Extractor(method, preset, sensor_profile=..., **params)(scan)``."""
    return Extractor(method, preset, sensor_profile=sensor_profile, **params)(scan)
