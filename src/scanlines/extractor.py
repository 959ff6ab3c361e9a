"""The one entry point: a configured :class:`Extractor`, and :func:`extract`."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from scanlines.errors import ParameterError, ScanError
from scanlines.extraction import Extraction, ExtractionTable
from scanlines.interrupts import kernel_calls
from scanlines.methods import REGISTRY, method_class
from scanlines.params import resolve
from scanlines.scan import Scan, as_array, valid_returns
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
        with kernel_calls:
            return self._method.extract(ranges, valid, cos, sin, step, angle_min)

    def warm_up(self) -> None:
        """Compile this extractor's kernels now (or load them from the cache), on a small
        synthetic scan, rather than on the first real one: a long first call is then
        not part of any timing, and no progress display is interrupted."""
        self(_warm_up_scan())

    def batch(
        self,
        ranges: np.ndarray,
        angle_min: float,
        angle_increment: float,
        range_min: float = 0.0,
        range_max: float = math.inf,
        *,
        jobs: int = 1,
    ) -> ExtractionTable:
        """Extract from a stack of scans of one sensor, ``ranges`` of shape (scans, beams).

        Gives exactly what calling the extractor on each row as a :class:`Scan` gives,
        without building the scans: the stack is validated once, the validity
        mask computed for all rows at once, the bearing tables shared, and the results
        are one flat :class:`~scanlines.extraction.ExtractionTable` (``table[i]`` is
        row ``i``'s :class:`Extraction`, built on access). ``jobs > 1`` splits the rows
        over that many threads (the kernels release the GIL); the table is the same.
        """
        stack = as_array(ranges, "ranges")
        if stack.ndim != 2:
            raise ScanError(f"ranges must be 2-D (scans, beams), got shape {stack.shape}")
        # Validate the sensor fields once, as Scan does (same errors).
        sensor = Scan(np.zeros(stack.shape[1]), angle_min, angle_increment, range_min, range_max)
        if stack.dtype.kind not in "fiu" or stack.dtype == np.bool_:
            raise ScanError(f"ranges must hold real numbers, got dtype {stack.dtype}")
        stack = at_float32(stack)
        valid = valid_returns(stack, float32(sensor.range_min), float32(sensor.range_max))
        step, angle_min = float32(sensor.angle_increment), float32(sensor.angle_min)
        cos, sin = self._bearings(stack.shape[1], step)
        if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
            raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}")
        parts = min(jobs, len(stack))
        if parts <= 1:
            with kernel_calls:
                return self._method.extract_many(stack, valid, cos, sin, step, angle_min)
        bounds = np.linspace(0, len(stack), parts + 1).astype(int)

        def part(k: int) -> ExtractionTable:
            rows = slice(bounds[k], bounds[k + 1])
            return self._method.extract_many(stack[rows], valid[rows], cos, sin, step, angle_min)

        with ThreadPoolExecutor(parts) as pool:
            return ExtractionTable.join(list(pool.map(part, range(parts))))

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


def _warm_up_scan() -> Scan:
    """A room 6 x 4 m with a box in it, seen at 1 deg over 270 deg, two beams lost."""
    bearings = np.radians(np.arange(-135.0, 135.5, 1.0))
    cos, sin = np.cos(bearings), np.sin(bearings)
    with np.errstate(divide="ignore"):
        walls = np.stack((np.where(cos > 0, 4.0, -2.0) / cos, np.where(sin > 0, 2.5, -1.5) / sin))
    ranges = np.where(walls > 0, walls, np.inf).min(axis=0)
    box = (bearings > 0.3) & (bearings < 0.5)
    ranges[box] = 2.0 / np.cos(bearings[box] - 0.4)
    ranges[[40, 41]] = 0.0
    return Scan(ranges, bearings[0], np.radians(1.0), range_max=30.0)


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
