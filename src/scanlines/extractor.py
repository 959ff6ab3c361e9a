"""The one entry point: a configured :class:`Extractor`, and :func:`extract`."""

from __future__ import annotations

import math
import struct
import sys
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from scanlines.builtin_methods import BUILTIN_METHODS, DEFAULT_METHOD
from scanlines.errors import ParameterError, ScanError
from scanlines.extraction import Extraction, ExtractionTable
from scanlines.methods import REGISTRY, method_class
from scanlines.params import param_lines, resolve
from scanlines.scan import Scan, as_array, valid_returns
from scanlines.sensor.learned_noise import Geometry, NoiseLearner
from scanlines.sensor.profile import SensorProfile, as_profile

__all__ = ["Extractor", "MethodInfo", "ParamInfo", "extract", "method_info", "method_names"]


def method_names() -> tuple[str, ...]:
    """Names of the registered methods."""
    return tuple(REGISTRY)


class ParamInfo(NamedTuple):
    """One parameter of a method: its default, what it does, the values it takes (in
    words, and as ``domain``: ``{"type": "float", "low": 0.0, "high": 90.0, ...}``) and
    its group (:data:`~scanlines.params.GROUPS`; ``""`` for a method declaring flat
    parameters); ``applies``: the other parameter whose value decides whether it is read
    (:attr:`scanlines.params.Param.applies`, kept only where the method has that other)."""

    default: Any
    doc: str
    allowed: str
    domain: dict[str, Any]
    group: str = ""
    applies: tuple[str, tuple[Any, ...], bool] | None = None


@dataclass(frozen=True)
class MethodInfo:
    """What :func:`method_info` returns; prints as a table. Items can also be read as
    ``info["params"]`` (``"name"``, ``"doc"``, ``"params"``, ``"presets"``)."""

    name: str
    doc: str
    params: dict[str, ParamInfo]
    presets: dict[str, dict[str, Any]]

    def __getitem__(self, key: str) -> Any:
        if key not in ("name", "doc", "params", "presets"):
            raise KeyError(key)
        return getattr(self, key)

    def __str__(self) -> str:
        rows = [(p.group, name, p.default, p.allowed, p.doc) for name, p in self.params.items()]
        lines = [f"{self.name}: {self.doc}", "", *param_lines(rows), ""]
        lines.append("presets: " + (", ".join(self.presets) or "none"))
        for preset, values in self.presets.items():
            shown = ", ".join(f"{k}={v!r}" for k, v in values.items())
            lines.append(f"  {preset}: {shown}")
        return "\n".join(lines)

    __repr__ = __str__


def method_info(method: str) -> MethodInfo:
    """The parameters of ``method`` (default, doc, allowed values) and its presets.

    Every value outside a parameter's domain (wrong type, out of bounds, inf, NaN) is a
    :class:`~scanlines.ParameterError` when an :class:`Extractor` is made, before
    anything runs. ``print(method_info("adaptive"))`` shows them as a table.
    """
    cls = method_class(method)
    module = sys.modules[cls.__module__]
    return MethodInfo(
        name=cls.name,
        doc=(module.__doc__ or cls.__doc__ or "").strip().splitlines()[0],
        params={
            name: ParamInfo(
                p.default,
                p.doc,
                p.check.describe(),
                p.check.domain(),
                cls.settings.group_of(name) if cls.settings else "",
                p.applies if p.applies and p.applies[0] in cls.parameters else None,
            )
            for name, p in cls.parameters.items()
        },
        presets={name: dict(values) for name, values in cls.presets.items()},
    )


class Extractor:
    """A configured extractor; call it on a :class:`~scanlines.Scan`.

    Parameters
    ----------
    method:
        A name from :func:`method_names`; ``"paper"`` is the paper's method as printed,
        ``"adaptive"`` the same steps changed to work on real logs.
    preset:
        A named parameter set of the method (``"paper"``: the paper, literally).
    sensor_profile:
        A :class:`~scanlines.sensor.profile.SensorProfile` (or the path of one saved
        by ``scanlines calibrate``): the range noise every threshold and covariance
        takes. Without one, each scan's noise is measured from that scan alone; a method
        that learns the noise (``surfaces``) takes each scan's noise from the sensor's
        scans before it, up to :data:`~scanlines.sensor.learned_noise.LEARNED_SCANS` of them
        (:class:`~scanlines.sensor.learned_noise.NoiseLearner`), then keeps that line; each
        thread learns from the scans it gave, so results do not depend on scheduling, and
        :meth:`batch` gives what the calls give.
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
        method: str = DEFAULT_METHOD,
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
        learns = self.sensor_profile is None and cls.learns_noise
        self._learner = NoiseLearner() if learns else None
        self._learned: dict[Any, Any] = {}  # noise line -> the method with it

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
        geometry = (len(scan), angle_min, step)
        extraction = self._method_for(geometry).extract(ranges, valid, cos, sin, step, angle_min)
        if self._learner is not None:
            self._learner.learn(geometry, ranges, valid, cos, sin)
        return extraction

    def _method_for(self, geometry: Geometry) -> Any:
        """The method to extract a scan of sensor ``geometry`` with: with the noise learned
        from the sensor's scans before it (in this thread), if the extractor learns it."""
        if self._learner is None:
            return self._method
        line = self._learner.line(geometry)
        if line is None:
            return self._method
        method = self._learned.get(line)
        if method is None:
            if len(self._learned) > 64:
                self._learned.clear()
            method = self._learned[line] = type(self._method)(self.params, line)
        return method

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
        mask computed for all rows at once, the bearing tables shared, a compiled
        method's kernel called once for the whole stack, and the results are one flat
        :class:`~scanlines.extraction.ExtractionTable` (``table[i]`` is
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
        tables, row = [], 0
        geometry = (stack.shape[1], angle_min, step)
        learner = self._learner
        while (
            learner is not None and row < len(stack) and not learner.frozen(geometry)
        ):  # the noise still learned: row by row
            rows = slice(row, row + 1)
            method = self._method_for(geometry)
            tables.append(method.extract_many(stack[rows], valid[rows], cos, sin, step, angle_min))
            learner.learn(geometry, stack[row], valid[row], cos, sin)
            row += 1
        if row < len(stack) or not tables:
            method, rows = self._method_for(geometry), slice(row, None)
            arrays = (stack[rows], valid[rows], cos, sin, step, angle_min)
            tables.append(_extract_stack(method, arrays, jobs))
        return tables[0] if len(tables) == 1 else ExtractionTable.join(tables)

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


def _extract_stack(method: Any, arrays: tuple[Any, ...], jobs: int) -> ExtractionTable:
    """``method`` on a stack of scans (stack, valid, cos, sin, step, angle_min), its rows
    split over ``jobs`` threads (the kernels release the GIL)."""
    stack, valid, *sensor = arrays
    parts = min(jobs, len(stack))
    if parts <= 1:
        return method.extract_many(stack, valid, *sensor)
    bounds = np.linspace(0, len(stack), parts + 1).astype(int)

    def part(k: int) -> ExtractionTable:
        rows = slice(bounds[k], bounds[k + 1])
        return method.extract_many(stack[rows], valid[rows], *sensor)

    with ThreadPoolExecutor(parts) as pool:
        return ExtractionTable.join(list(pool.map(part, range(parts))))


def float32(value: float) -> float:
    """``value`` rounded to float32 precision (infinities stay; beyond float32's range a
    range bound becomes infinite, which it is for every float32 range)."""
    try:
        return struct.unpack("f", struct.pack("f", value))[0]
    except OverflowError:  # rounds beyond float32's largest value, as numpy's cast does
        return math.copysign(math.inf, value)


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
    method: str = DEFAULT_METHOD,
    preset: str | None = None,
    *,
    sensor_profile: SensorProfile | str | Path | None = None,
    **params: Any,
) -> Extraction:
    """Line segments, breakpoints and corners of one scan.

    The one-shot form of :class:`Extractor` (``Extractor(method, preset,
    sensor_profile=..., **params)(scan)``); make an :class:`Extractor` once to extract
    many scans (it keeps its bearing tables).

    Parameters
    ----------
    scan:
        The :class:`~scanlines.Scan`.
    method:
        ``"adaptive"`` (the paper's steps, each changed where real noisy scans need it;
        the method as printed is ``paper``), or another of :func:`method_names`:
        {other_methods}.
    preset:
        A named parameter set of the method; ``"paper"`` runs the adaptive method
        exactly as published.
    sensor_profile:
        A :class:`~scanlines.sensor.profile.SensorProfile`, or the path of one saved
        by ``scanlines calibrate``: the range noise thresholds and covariances use.
        Without one, the noise is measured from the scan itself.
    **params:
        Single parameters of the method, e.g. ``k=3.0``, ``min_points=5``,
        ``fit="tls"``. ``print(scanlines.method_info(method))`` lists every one with
        its default, meaning and allowed values.

    Returns
    -------
    Extraction
        ``segments`` (each with its line, end points, covariance and what ends it),
        ``breakpoints`` and ``corners`` (beam indices), ``params`` (every resolved
        parameter).

    Raises
    ------
    ScanError
        ``scan`` is not a :class:`~scanlines.Scan`.
    ParameterError
        An unknown method, preset or parameter, or a value outside its domain (wrong
        type, out of bounds, inf, NaN), before anything runs.

    Examples
    --------
    A SICK-like 180 degree scan of a wall 2 m ahead and side walls 1.5 m away:

    >>> import numpy as np
    >>> from scanlines import Scan, extract
    >>> bearings = np.radians(np.arange(-90, 91))
    >>> across, along = np.abs(np.sin(bearings)) + 1e-12, np.abs(np.cos(bearings)) + 1e-12
    >>> ranges = np.minimum(2.0 / along, 1.5 / across)
    >>> scan = Scan(ranges, angle_min=-np.pi / 2, angle_increment=np.pi / 180, range_max=30.0)
    >>> result = extract(scan)
    >>> [round(s.rho, 3) for s in result.segments], result.corners.tolist()
    ([1.5, 2.0, 1.5], [53, 127])
    >>> len(extract(scan, "partition").segments)
    3
    """
    return Extractor(method, preset, sensor_profile=sensor_profile, **params)(scan)


def _spelled(names: tuple[str, ...]) -> str:
    """``"a"``, ``"b"``... wrapped as the docstring's lines are."""
    import textwrap

    listed = ", ".join(f'``"{name}"``' for name in names)
    return textwrap.fill(listed, width=80, subsequent_indent=" " * 8, break_on_hyphens=False)


# The methods named in extract's help are the built-in ones (the registry's, tested).
extract.__doc__ = (extract.__doc__ or "").replace(
    "{other_methods}", _spelled(tuple(m for m in BUILTIN_METHODS if m != DEFAULT_METHOD))
)
