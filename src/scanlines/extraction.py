"""The result type: segments, breakpoints and corners of one scan."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from scanlines.report import jsonable

__all__ = ["END_KINDS", "Extraction", "ExtractionTable", "Segment"]

# Columns of Extraction.lines, one row per segment.
RHO, ALPHA, START_X, START_Y, END_X, END_Y, RMS = range(7)
N_LINE_COLUMNS = 7

END_KINDS = ("corner", "jump", "occluded", "gap", "edge", "open")
"""What ends a segment (the codes of :attr:`Extraction.end_kinds`):

``corner``    two surfaces meet at a corner within one beam;
``jump``      a depth jump to a farther surface: this surface really ends here;
``occluded``  a depth jump to a nearer surface: this one may go on behind it;
``gap``       two or more beams without a return follow;
``edge``      the scan's first or last return;
``open``      none of these: the method stopped on a continuing surface (a curve,
              clutter, a point dropped as noise).

Mapping and SLAM front ends can trust ``corner`` and ``jump`` ends as real endpoints."""


@dataclass(frozen=True, slots=True)
class Segment:
    """One fitted line segment.

    Attributes
    ----------
    first, last:
        Inclusive beam indices. ``first > last`` only for the segment that
        crosses the seam of a full-circle scan (it runs from ``first`` to the
        last beam and on from beam 0 to ``last``).
    start, end:
        ``(x, y)`` of the first and last points projected onto the line.
    rho, alpha:
        Hesse normal form ``x cos(alpha) + y sin(alpha) = rho``, ``rho >= 0``,
        ``alpha`` in ``(-pi, pi]``.
    n_points:
        Points the line was fitted to.
    rms:
        Root-mean-square orthogonal distance of those points to the line.
    covariance:
        2 x 2 covariance of ``(rho, alpha)``, propagated from the range noise of each
        return (the sensor profile's noise line, or ``range_sigma``), scaled up when
        the segment's own residuals are larger than that noise explains.
    start_kind, end_kind:
        What ends the segment at ``first`` and at ``last`` (:data:`END_KINDS`).
    """

    first: int
    last: int
    start: tuple[float, float]
    end: tuple[float, float]
    rho: float
    alpha: float
    n_points: int
    rms: float
    covariance: np.ndarray
    start_kind: str = "open"
    end_kind: str = "open"

    @property
    def length(self) -> float:
        """Distance from ``start`` to ``end`` in metres."""
        return math.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1])


class Extraction:
    """Features of one scan, as arrays, with :class:`Segment` views built on access.

    Attributes
    ----------
    breakpoints:
        One beam index per gap: the last valid beam before it.
    corners:
        Beam index of each corner (the beam nearer the true corner).
    outliers:
        Beams rejected as isolated noise points; they belong to no segment.
    first, last, n_points:
        Per-segment integer arrays (see :class:`Segment`).
    lines:
        ``M x 7`` float array: rho, alpha, start x, start y, end x, end y, rms.
    covariances:
        ``M x 2 x 2`` covariances of ``(rho, alpha)``.
    end_kinds:
        ``M x 2`` codes of what ends each segment at its first and last beam (an index
        into :data:`END_KINDS`).
    method:
        Name of the method that produced it.
    params:
        The full resolved parameters (read-only mapping).
    """

    __slots__ = (
        "_segments",
        "breakpoints",
        "corners",
        "covariances",
        "end_kinds",
        "first",
        "last",
        "lines",
        "method",
        "n_points",
        "outliers",
        "params",
    )

    def __init__(
        self,
        *,
        first: np.ndarray,
        last: np.ndarray,
        n_points: np.ndarray,
        lines: np.ndarray,
        covariances: np.ndarray,
        breakpoints: np.ndarray,
        corners: np.ndarray,
        outliers: np.ndarray,
        method: str,
        params: Mapping[str, Any],
        end_kinds: np.ndarray | None = None,
    ) -> None:
        self.first = _frozen(first, np.intp)
        self.last = _frozen(last, np.intp)
        self.n_points = _frozen(n_points, np.intp)
        self.lines = _frozen(lines, np.float64).reshape(-1, N_LINE_COLUMNS)
        self.covariances = _frozen(covariances, np.float64).reshape(-1, 2, 2)
        self.breakpoints = _frozen(breakpoints, np.intp)
        self.corners = _frozen(corners, np.intp)
        self.outliers = _frozen(outliers, np.intp)
        if end_kinds is None:
            end_kinds = np.full((len(self.first), 2), END_KINDS.index("open"))
        self.end_kinds = _frozen(end_kinds, np.int8).reshape(-1, 2)
        self.method = method
        self.params = _read_only(params)
        self._segments: tuple[Segment, ...] | None = None

    @classmethod
    def _of_frozen(cls, arrays: Sequence[np.ndarray], method: str, params: MappingProxyType):
        """An extraction of arrays already read-only and of the right dtypes and shapes
        (in the order of ``_ARRAYS``): no copies, no checks (:class:`ExtractionTable`)."""
        self = cls.__new__(cls)
        for name, values in zip(_ARRAYS, arrays, strict=True):
            object.__setattr__(self, name, values)
        self.method, self.params, self._segments = method, params, None
        return self

    @classmethod
    def of_flat_table(cls, table: Sequence[np.ndarray], method: str, params: Mapping[str, Any]):
        """The extraction of a stack kernel's table of one scan
        (:mod:`scanlines.steps.stack`), whose arrays it takes over: views, made read-only."""
        arrays = _flat_columns(table)
        for values in arrays:
            values.setflags(write=False)
        return cls._of_frozen(arrays, method, _read_only(params))

    @property
    def segments(self) -> tuple[Segment, ...]:
        """Segments in beam-index order (``segments[k].last <= segments[k+1].first``)."""
        if self._segments is None:
            self._segments = tuple(self._segment(k) for k in range(len(self.first)))
        return self._segments

    def _segment(self, k: int) -> Segment:
        row = self.lines[k]
        return Segment(
            first=int(self.first[k]),
            last=int(self.last[k]),
            start=(float(row[START_X]), float(row[START_Y])),
            end=(float(row[END_X]), float(row[END_Y])),
            rho=float(row[RHO]),
            alpha=float(row[ALPHA]),
            n_points=int(self.n_points[k]),
            rms=float(row[RMS]),
            covariance=self.covariances[k],
            start_kind=END_KINDS[self.end_kinds[k, 0]],
            end_kind=END_KINDS[self.end_kinds[k, 1]],
        )

    def __len__(self) -> int:
        return len(self.first)

    def __reduce__(self) -> tuple[Any, ...]:
        # Pickle by the constructor's arguments (process pools); Segment views are rebuilt.
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        return _rebuild_extraction, (arrays, self.method, dict(self.params))

    def __repr__(self) -> str:
        return (
            f"Extraction(method={self.method!r}, segments={len(self)}, "
            f"breakpoints={len(self.breakpoints)}, corners={len(self.corners)})"
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (JSON-serialisable)."""
        return {
            "method": self.method,
            "params": {k: jsonable(v) for k, v in self.params.items()},
            "segments": [
                {
                    "first": s.first,
                    "last": s.last,
                    "start": list(s.start),
                    "end": list(s.end),
                    "rho": s.rho,
                    "alpha": s.alpha,
                    "n_points": s.n_points,
                    "rms": s.rms,
                    "length": s.length,
                    "covariance": s.covariance.tolist(),
                    "start_kind": s.start_kind,
                    "end_kind": s.end_kind,
                }
                for s in self.segments
            ],
            "breakpoints": self.breakpoints.tolist(),
            "corners": self.corners.tolist(),
            "outliers": self.outliers.tolist(),
        }


_ARRAYS = (
    *("first", "last", "n_points", "lines", "covariances"),
    *("breakpoints", "corners", "outliers", "end_kinds"),
)


def _rebuild_extraction(
    arrays: dict[str, np.ndarray], method: str, params: dict[str, Any]
) -> Extraction:
    return Extraction(**arrays, method=method, params=params)


def _frozen(values: np.ndarray, dtype: type) -> np.ndarray:
    arr = np.ascontiguousarray(values, dtype=dtype)
    if arr.flags.writeable:
        arr.setflags(write=False)
    return arr


SEGMENT_COLUMNS = ("first", "last", "n_points", "lines", "covariances", "end_kinds")
"""The per-segment arrays of :class:`Extraction` and :class:`ExtractionTable`."""
EVENT_COLUMNS = ("breakpoints", "corners", "outliers")
"""The per-scan event arrays (beam indices)."""
_DTYPES = {
    "first": np.intp, "last": np.intp, "n_points": np.intp, "lines": np.float64,
    "covariances": np.float64, "end_kinds": np.int8,
    "breakpoints": np.intp, "corners": np.intp, "outliers": np.intp,
}  # fmt: skip
_ROW_SHAPES = {"lines": (N_LINE_COLUMNS,), "covariances": (2, 2), "end_kinds": (2,)}


class ExtractionTable(Sequence[Extraction]):
    """Features of a stack of scans as one flat table; ``table[i]`` is scan ``i``'s
    :class:`Extraction` (a view, built on access).

    Attributes
    ----------
    first, last, n_points, lines, covariances, end_kinds:
        The segments of every scan, scan after scan (the columns of :class:`Extraction`).
    segment_offsets:
        ``scans + 1`` indices: scan ``i``'s segments are rows
        ``segment_offsets[i]:segment_offsets[i + 1]``.
    breakpoints, corners, outliers:
        Beam indices of every scan, scan after scan, with ``breakpoint_offsets``,
        ``corner_offsets`` and ``outlier_offsets`` the same way.
    method, params:
        As in :class:`Extraction`.
    """

    def __init__(self, columns: Mapping[str, np.ndarray], offsets: Mapping[str, np.ndarray],
                 method: str, params: Mapping[str, Any]) -> None:  # fmt: skip
        self.columns = {name: _frozen(columns[name], _DTYPES[name]) for name in _ARRAYS}
        for name, shape in _ROW_SHAPES.items():
            self.columns[name] = self.columns[name].reshape(-1, *shape)
        self.offsets = {
            name: _frozen(offsets[name], np.intp) for name in ("segments", *EVENT_COLUMNS)
        }
        self.method = method
        self.params = _read_only(params)

    @classmethod
    def of_flat_table(cls, table: Sequence[np.ndarray], method: str,
                      params: Mapping[str, Any]) -> ExtractionTable:  # fmt: skip
        """The table of a stack kernel's output (:mod:`scanlines.steps.stack`)."""
        columns = dict(zip(_ARRAYS, _flat_columns(table), strict=True))
        counts = table[9]
        offsets = {
            name: _offsets(counts[:, k]) for k, name in enumerate(("segments", *EVENT_COLUMNS))
        }
        return cls(columns, offsets, method, params)

    @classmethod
    def concatenate(cls, rows: Sequence[Sequence[np.ndarray] | Extraction], method: str,
                    params: Mapping[str, Any]) -> ExtractionTable:  # fmt: skip
        """The table of per-scan results: extractions, or tuples of their arrays in the
        order of a kernel's result (``first, last, n_points, lines, covariances,
        breakpoints, corners, outliers, end_kinds``)."""
        rows = [
            tuple(getattr(row, name) for name in _ARRAYS) if isinstance(row, Extraction) else row
            for row in rows
        ]
        columns, offsets = {}, {}
        for column, name in enumerate(_ARRAYS):
            parts = [row[column] for row in rows]
            empty = np.zeros((0, *_ROW_SHAPES.get(name, ())), _DTYPES[name])
            columns[name] = np.concatenate(parts) if parts else empty
            if name == "first" or name in EVENT_COLUMNS:
                key = "segments" if name == "first" else name
                offsets[key] = _offsets([len(part) for part in parts])
        return cls(columns, offsets, method, params)

    @classmethod
    def join(cls, tables: Sequence[ExtractionTable]) -> ExtractionTable:
        """One table of the scans of ``tables``, in order (all of one method)."""
        columns = {name: np.concatenate([t.columns[name] for t in tables]) for name in _ARRAYS}
        offsets = {}
        for key in tables[0].offsets:
            starts = np.cumsum([0] + [t.offsets[key][-1] for t in tables[:-1]])
            parts = [t.offsets[key][1:] + start for t, start in zip(tables, starts, strict=True)]
            offsets[key] = np.concatenate([[0], *parts])
        return cls(columns, offsets, tables[0].method, tables[0].params)

    def __len__(self) -> int:
        return len(self.offsets["segments"]) - 1

    def __getitem__(self, index: int) -> Extraction:  # type: ignore[override]
        if isinstance(index, slice):
            raise TypeError("ExtractionTable takes one scan index, not a slice")
        n = len(self)
        if not -n <= index < n:
            raise IndexError(f"scan {index} out of range for a table of {n} scans")
        index %= n
        arrays = []
        for name in _ARRAYS:
            key = "segments" if name in SEGMENT_COLUMNS else name
            start, stop = self.offsets[key][index], self.offsets[key][index + 1]
            arrays.append(self.columns[name][start:stop])
        return Extraction._of_frozen(arrays, self.method, self.params)

    def __iter__(self) -> Iterator[Extraction]:
        return (self[i] for i in range(len(self)))

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["columns"][name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def segment_scan(self) -> np.ndarray:
        """The stack row (scan) of each segment."""
        return np.repeat(np.arange(len(self)), np.diff(self.offsets["segments"]))

    def counts(self, name: str = "segments") -> np.ndarray:
        """Per scan: how many ``segments`` (or ``breakpoints``, ``corners``, ``outliers``)."""
        return np.diff(self.offsets[name])

    def __reduce__(self) -> tuple[Any, ...]:
        return ExtractionTable, (self.columns, self.offsets, self.method, dict(self.params))

    def __repr__(self) -> str:
        segments = len(self.first)
        return f"ExtractionTable(method={self.method!r}, scans={len(self)}, segments={segments})"


def _flat_columns(table: Sequence[np.ndarray]) -> list[np.ndarray]:
    """The columns of a stack kernel's table, in ``_ARRAYS`` order: views of its used
    part, shaped as :class:`ExtractionTable`'s."""
    segments, breakpoints, corners, outliers = table[10].tolist()
    first, last, n_points, lines, covariances, *events, end_kinds = table[:9]
    return [
        first[:segments],
        last[:segments],
        n_points[:segments],
        lines[: segments * N_LINE_COLUMNS].reshape(segments, N_LINE_COLUMNS),
        covariances[: segments * 4].reshape(segments, 2, 2),
        events[0][:breakpoints],
        events[1][:corners],
        events[2][:outliers],
        end_kinds[: segments * 2].reshape(segments, 2),
    ]


def _read_only(params: Mapping[str, Any]) -> MappingProxyType:
    return params if isinstance(params, MappingProxyType) else MappingProxyType(dict(params))


def _offsets(counts: list[int]) -> np.ndarray:
    offsets = np.zeros(len(counts) + 1, dtype=np.intp)
    np.cumsum(counts, out=offsets[1:])
    return offsets
