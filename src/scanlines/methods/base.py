"""What every method is: the :class:`Method` protocol and its two kinds of implementation.

A method is a class with a ``name``, its ``settings`` (a
:class:`~scanlines.params.Settings`: its parameters grouped by purpose, declared in its
module), named ``presets`` and :meth:`Method.extract`, which goes from one scan's arrays to
an :class:`~scanlines.Extraction`. An instance holds resolved, validated parameters;
:class:`~scanlines.Extractor` builds it once and calls it per scan. Nothing here names a
parameter: a method's settings are read by name only in its module and its kernel.

:class:`CompiledMethod`
    The whole method is one compiled kernel (adaptive, paper, iepf, pdbs, split_merge,
    partition, surfaces; C++ in ``cpp/scanlines/methods/``), called once per stack of scans
    without the GIL. Its settings become one record per group, the fields each parameter
    declares (:meth:`~scanlines.params.Settings.record`), which the kernel's binding reads
    into its typed settings by name.
:class:`ClusteredMethod`
    The method's own search is Python over numpy (line tracking, line regression,
    RANSAC, Hough); clustering before it and the events and assembly after it are the
    shared compiled steps, so that no step exists twice.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np

from scanlines import _core
from scanlines.extraction import Extraction, ExtractionTable
from scanlines.params import Param, Settings, kernel_settings
from scanlines.scan import is_full_circle
from scanlines.steps.assemble import Output, empty_result, finish, to_extraction
from scanlines.steps.breakpoints import NO_RULE, RuleSpec
from scanlines.steps.noise import UNKNOWN_NOISE, NoiseLine
from scanlines.steps.returns import Returns, beam_gaps, valid_returns, without

__all__ = [
    "NO_CLUSTERING",
    "ClusteredMethod",
    "CompiledMethod",
    "Method",
    "cluster_scan",
    "kernel_tuple",
]

NO_CLUSTERING = "none"
"""The ``breakpoints`` value of a method that works on the whole scan."""


class Method:
    """An extractor configured with resolved parameters (see the module docstring).

    A subclass sets ``name``, ``parameters`` and (optionally) ``presets`` and
    implements :meth:`extract`.
    """

    name: ClassVar[str] = ""
    #: The parameters grouped by purpose; a method of your own may declare the flat
    #: ``parameters`` instead (its kernel then reads one flat record).
    settings: ClassVar[Settings | None] = None
    #: Every parameter, name -> :class:`~scanlines.params.Param` (from ``settings``).
    parameters: ClassVar[Mapping[str, Param]] = {}
    presets: ClassVar[Mapping[str, Mapping[str, Any]]] = {}
    #: Whether an Extractor without a sensor profile learns the noise line from its first
    #: scans for this method (:class:`~scanlines.sensor.learned_noise.NoiseLearner`).
    learns_noise: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "settings" in cls.__dict__ and cls.settings is not None:
            cls.parameters = cls.settings.parameters

    def __init__(self, params: Mapping[str, Any], noise: NoiseLine | None = None) -> None:
        self.params = params
        self.noise = UNKNOWN_NOISE if noise is None else NoiseLine(*map(float, noise))

    @classmethod
    def record_of(cls, params: Mapping[str, Any]) -> dict[str, Any]:
        """The kernel's settings of resolved ``params``: group -> field -> plain Python number
        (a method declaring flat ``parameters``: field -> such a number)."""
        if cls.settings is None:
            return kernel_settings(cls.parameters, params)
        return cls.settings.record(params)

    def extract(
        self,
        ranges: np.ndarray,
        valid: np.ndarray,
        cos: np.ndarray,
        sin: np.ndarray,
        step: float,
        angle_min: float,
    ) -> Extraction:
        """Features of one scan.

        ``ranges`` and the mask ``valid`` of beams with a return (float64 and bool,
        C-contiguous), ``cos, sin`` the bearing tables of the beams relative to beam
        0, ``step`` the angular increment (its sign is ignored), ``angle_min`` the
        bearing of beam 0 (results are in the sensor frame).
        """
        raise NotImplementedError

    def extract_many(
        self,
        stack: np.ndarray,
        valid: np.ndarray,
        cos: np.ndarray,
        sin: np.ndarray,
        step: float,
        angle_min: float,
    ) -> ExtractionTable:
        """:meth:`extract` of each row of a stack of scans of one sensor, as one table."""
        rows = [
            self.extract(row, mask, cos, sin, step, angle_min)
            for row, mask in zip(stack, valid, strict=True)
        ]
        return ExtractionTable.concatenate(rows, self.name, self.params)


class CompiledMethod(Method):
    """A method that is one kernel from a stack of scans' arrays to one flat table.

    A subclass sets ``kernel(stack, valid, cos, sin, step, full_circle,
    angle_min, noise, *arguments)`` as a ``staticmethod``: the method's compiled stack
    kernel, a loop over the rows of its per-scan kernel that returns one flat table
    (:meth:`~scanlines.extraction.ExtractionTable.of_flat_table` reads it). One scan is a
    stack of one. :meth:`kernel_arguments` returns the kernel's last arguments, by
    default the record of :meth:`record_of` (group -> the fields its parameters declare,
    as plain numbers by name; a subclass may add arguments of its own).
    """

    def __init__(self, params: Mapping[str, Any], noise: NoiseLine | None = None) -> None:
        super().__init__(params, noise)
        self.record = self.record_of(params)
        self.arguments = self.kernel_arguments()

    def kernel_arguments(self) -> tuple[Any, ...]:
        return (self.record,)

    @staticmethod
    def kernel(*args: Any) -> tuple[np.ndarray, ...]:
        raise NotImplementedError

    def extract(self, ranges, valid, cos, sin, step, angle_min) -> Extraction:
        table = self._stack_table(ranges[np.newaxis], valid[np.newaxis], cos, sin, step, angle_min)
        return Extraction.of_flat_table(table, self.name, self.params)

    def extract_many(self, stack, valid, cos, sin, step, angle_min) -> ExtractionTable:
        table = self._stack_table(stack, valid, cos, sin, step, angle_min)
        return ExtractionTable.of_flat_table(table, self.name, self.params)

    def _stack_table(self, stack, valid, cos, sin, step, angle_min) -> tuple[np.ndarray, ...]:
        full_circle = is_full_circle(stack.shape[1], step)
        return self.kernel(
            stack, valid, cos, sin, abs(step), full_circle, angle_min, self.noise, *self.arguments
        )


def kernel_tuple(kind: type[NamedTuple], *groups: Mapping[str, Any]):
    """The kernel tuple ``kind`` (:class:`~scanlines.steps.breakpoints.RuleSpec`,
    :class:`~scanlines.steps.assemble.Output`) of the fields of the settings records
    ``groups`` that it names."""
    fields = {name: value for group in groups for name, value in group.items()}
    return kind(**{name: fields[name] for name in kind._fields})


class ClusteredMethod(Method):
    """A method whose own search (:meth:`find_runs`) is Python over numpy.

    :meth:`extract` clusters the scan's returns by the method's ``breakpoints`` rule
    (``"none"``: one cluster of every return), calls :meth:`find_runs`, and finishes
    with the shared kernels: small runs dropped, corners (and, without clustering,
    breakpoints) between consecutive segments, lines fitted and assembled.
    """

    def __init__(self, params: Mapping[str, Any], noise: NoiseLine | None = None) -> None:
        super().__init__(params, noise)
        record = self.record_of(params)
        group = (lambda name: record[name]) if self.settings else (lambda name: record)
        self.rule = kernel_tuple(RuleSpec, group("clustering"))
        self.output = kernel_tuple(Output, group("output"), group("events"))

    def find_runs(
        self, returns: Returns, gap: np.ndarray, start: np.ndarray, end: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Segments of the clusters ``[start[c], end[c]]`` of ``returns`` (``gap``: beams
        between consecutive positions).

        Returns ``a, b, group, dropped``: the runs ``[a, b]`` (positions, in order of
        ``a``), the cluster of each, and the positions to drop as outliers (none of
        them a run's first or last position).
        """
        raise NotImplementedError

    def extract(self, ranges, valid, cos, sin, step, angle_min) -> Extraction:
        n_beams, step = ranges.shape[0], abs(step)
        full_circle = is_full_circle(n_beams, step)
        returns = valid_returns(ranges, valid, cos, sin)
        none = np.zeros(0, dtype=np.int64)
        if returns.index.shape[0] == 0:
            return to_extraction(empty_result(none, none), self.name, self.params)
        returns, start, end, breakpoints, ring = cluster_scan(
            returns, n_beams, step, full_circle, self.rule, self.noise
        )
        gap = beam_gaps(returns.index, n_beams)
        a, b, group, dropped = (
            np.ascontiguousarray(v, dtype=np.int64)
            for v in self.find_runs(returns, gap, start, end)
        )
        outliers = returns.index[dropped]
        if dropped.size:
            returns, a, b = _without_positions(returns, a, b, dropped)
        arrays = finish(
            returns, n_beams, full_circle, (a, b, group),
            (self.rule.breakpoints != NO_RULE, ring, breakpoints), outliers, angle_min, self.output,
            self.noise,
        )  # fmt: skip
        return to_extraction(arrays, self.name, self.params)


def _without_positions(returns: Returns, a: np.ndarray, b: np.ndarray, drop: np.ndarray):
    """The returns without positions ``drop``, and the runs ``[a, b]`` renumbered."""
    mask = np.zeros(returns.index.shape[0], dtype=bool)
    mask[drop] = True
    new_position = np.cumsum(~mask) - 1
    return without(returns, mask), new_position[a], new_position[b]


def cluster_scan(returns, n_beams, step, full_circle, spec, noise):
    """The returns clustered by the rule of the
    :class:`~scanlines.steps.breakpoints.RuleSpec` ``spec``, its noise from the scan:
    ``(returns, start, end, breakpoints, ring)``
    (``cluster_returns``; a ring is anchored by lines of
    five points on each side).

    :data:`~scanlines.steps.breakpoints.NO_RULE` makes one cluster of every return (a
    full circle is still rotated to start after a gap or at its strongest corner).
    """
    rotated, start, end, breakpoints, ring = _core.cluster_scan(
        *returns, int(n_beams), float(step), bool(full_circle), spec._asdict(), tuple(noise)
    )
    return Returns(*rotated), start, end, breakpoints, ring
