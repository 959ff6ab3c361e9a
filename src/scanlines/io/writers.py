"""Writing extraction results: JSON Lines, CSV, and ROS 2 bags with markers.

Use :func:`scanlines.io.open_writer`; it picks the format from the output path
(the ROS 2 writer is :mod:`scanlines.io.bag_writer`):

============================  =================================================
``*.jsonl``                   one JSON object per written scan
``*.csv``                     one row per segment
``*.mcap``                    a single MCAP file (ROS 2 messages)
a path without suffix         a ROS 2 bag directory (``storage="mcap"`` or
                              ``"sqlite3"``)
============================  =================================================

Every writer streams (one scan in memory at a time) and is atomic: output
goes to a hidden temporary file or directory next to the target and is moved
into place by ``os.replace`` only when the writer is closed without error; an
exception inside the ``with`` block (or :meth:`ResultWriter.abort`) deletes
it, leaving neither output nor ``.meta.json`` behind.

Beside every output, ``<output>.meta.json`` (e.g. ``result.jsonl.meta.json``)
records ``format_version``, ``scanlines_version``, the output format and
frame, the caller's ``meta`` (input file, method, full parameters, reader
options...) and ``counts`` (scans, segments, breakpoints, corners written,
plus caller counts such as skipped records, see
:meth:`ResultWriter.update_meta`). ``method`` and ``params`` default to those
of the first extraction written.

Frames
------
Pass extractions in the sensor frame, as :func:`scanlines.extract` returns
them. With ``frame="world"`` the writer moves segments (with
:func:`scanlines.io.transform.to_world`) and breakpoint/corner points into the
log's world frame using ``scan.pose``; a scan without a pose is then an error.
Do not transform beforehand as well.

Record layouts
--------------
JSON Lines: ``{"scan", "timestamp", "pose", "segments": [{"first", "last",
"start", "end", "rho", "alpha", "n_points", "rms", "covariance", "start_kind",
"end_kind"}], "breakpoints", "corners"}``, where ``scan`` is the record index in the
log, breakpoints and corners are beam indices, ``covariance`` is the 2 x 2
covariance of ``(rho, alpha)`` as ``[[var_rho, cov], [cov, var_alpha]]``, the kinds
say what ends the segment (:data:`scanlines.extraction.END_KINDS`), and missing or
non-finite numbers are ``null``.

CSV columns: ``scan,timestamp,first,last,start_x,start_y,end_x,end_y,rho,alpha,n_points,rms,
var_rho,cov_rho_alpha,var_alpha,start_kind,end_kind``; missing or non-finite values
are empty cells. A scan without segments writes no row.

ROS 2 (``rosbags.rosbag2.Writer``, ``Stores.ROS2_HUMBLE`` types), per scan,
stamped with the scan time (``index * 0.1`` s when the scan has none):

* the input scan as ``sensor_msgs/msg/LaserScan`` on ``topic`` (``/scan``),
  frame ``laser_frame`` (``"laser"``), ranges unchanged as float32;
* a ``visualization_msgs/msg/MarkerArray`` on ``/scanlines/markers``: a
  ``DELETEALL`` marker, then (only when non-empty) namespace ``segments``
  (``LINE_LIST``, green, two points per segment), ``breakpoints``
  (``SPHERE_LIST``, red) and ``corners`` (``SPHERE_LIST``, blue), in frame
  ``laser_frame`` or, with ``frame="world"``, ``world_frame`` (``"map"``);
* the scan's JSON Lines record (above: every segment with its covariance and end
  kinds) as ``std_msgs/msg/String`` on ``/scanlines/features``;
* when the scan has a pose, a ``tf2_msgs/msg/TFMessage`` on ``/tf`` from
  ``world_frame`` to ``laser_frame``, so Foxglove/RViz can place the scan.

Bag readers return messages in time order, so scans whose timestamps go
backwards (the Intel raw log) come back sorted by time from the bag. The
``.mcap`` file and the bag directory get the usual permissions (``0o666``
less the umask); so do the text outputs and the ``.meta.json``.
"""

from __future__ import annotations

import csv
import json
import math
import os
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import IO, Any, ClassVar, Literal, Self

import numpy as np

from scanlines.errors import ParameterError
from scanlines.extraction import (
    ALPHA,
    END_KINDS,
    END_X,
    END_Y,
    RHO,
    RMS,
    START_X,
    START_Y,
    Extraction,
)
from scanlines.io.transform import points_to_world, to_world
from scanlines.json_values import jsonable
from scanlines.scan import Scan

__all__ = [
    "CSV_COLUMNS",
    "META_FORMAT_VERSION",
    "CsvWriter",
    "JsonlWriter",
    "ResultWriter",
    "meta_path_for",
]

Frame = Literal["sensor", "world"]

#: Version of the ``.meta.json`` layout.
META_FORMAT_VERSION = 1
#: Columns of the CSV output, in order.
CSV_COLUMNS = (
    "scan",
    "timestamp",
    "first",
    "last",
    "start_x",
    "start_y",
    "end_x",
    "end_y",
    "rho",
    "alpha",
    "n_points",
    "rms",
    "var_rho",
    "cov_rho_alpha",
    "var_alpha",
    "start_kind",
    "end_kind",
)
#: Bag time step used for scans without a timestamp (seconds per record index).
UNSTAMPED_PERIOD = 0.1


def meta_path_for(path: str | Path) -> Path:
    """The ``.meta.json`` written beside ``path``: ``<path>.meta.json``."""
    path = Path(path)
    return path.with_name(path.name + ".meta.json")


@dataclass(frozen=True)
class ScanFeatures:
    """What a writer needs from one scan, in the output frame.

    Attributes
    ----------
    index, scan:
        Record index in the log and the scan itself.
    extraction:
        Features, transformed to the output frame.
    breakpoint_points, corner_points:
        ``K x 2`` positions of the breakpoint and corner beams in the output frame.
    """

    index: int
    scan: Scan
    extraction: Extraction
    breakpoint_points: np.ndarray
    corner_points: np.ndarray


def _beam_points(scan: Scan, indices: np.ndarray) -> np.ndarray:
    """Points of the beams ``indices`` that have a return (rows of ``scan.points``)."""
    indices = np.asarray(indices, dtype=np.intp)
    inside = indices[(indices >= 0) & (indices < len(scan))]
    beams = inside[scan.valid[inside]]
    # the same arithmetic as Scan.points, for these beams only
    r = scan.ranges[beams]
    angles = scan.angle_min + scan.angle_increment * beams.astype(np.float64)
    points = np.column_stack((r * np.cos(angles), r * np.sin(angles)))
    return points[np.isfinite(points).all(axis=1)]


def _features(index: int, scan: Scan, extraction: Extraction, frame: Frame) -> ScanFeatures:
    breakpoints = _beam_points(scan, extraction.breakpoints)
    corners = _beam_points(scan, extraction.corners)
    if frame == "world":
        if scan.pose is None:
            raise ParameterError(
                f"frame='world' needs scan poses, but scan {index} has none; use frame='sensor'"
            )
        extraction = to_world(extraction, scan.pose)
        breakpoints = points_to_world(breakpoints, scan.pose)
        corners = points_to_world(corners, scan.pose)
    return ScanFeatures(index, scan, extraction, breakpoints, corners)


def json_record(features: ScanFeatures) -> str:
    """The JSON Lines record of one scan (the module docstring), without the newline."""
    scan, extraction = features.scan, features.extraction
    covariances = _finite_rows(extraction.covariances.reshape(-1, 4))
    record = {
        "scan": int(features.index),
        "timestamp": None if scan.timestamp is None else _number(scan.timestamp),
        "pose": None if scan.pose is None else [_number(v) for v in scan.pose],
        "segments": [
            {
                "first": first,
                "last": last,
                "start": [row[START_X], row[START_Y]],
                "end": [row[END_X], row[END_Y]],
                "rho": row[RHO],
                "alpha": row[ALPHA],
                "n_points": n_points,
                "rms": row[RMS],
                "covariance": [cov[:2], cov[2:]],
                "start_kind": END_KINDS[kinds[0]],
                "end_kind": END_KINDS[kinds[1]],
            }
            for first, last, n_points, row, cov, kinds in zip(
                extraction.first.tolist(),
                extraction.last.tolist(),
                extraction.n_points.tolist(),
                _finite_rows(extraction.lines),
                covariances,
                extraction.end_kinds.tolist(),
                strict=True,
            )
        ],
        "breakpoints": extraction.breakpoints.tolist(),
        "corners": extraction.corners.tolist(),
    }
    return json.dumps(record, allow_nan=False, separators=(",", ":"))


def _finite_rows(table: np.ndarray) -> list[list[float | None]]:
    """Rows of a float table as lists, NaN and infinities as None."""
    if np.isfinite(table).all():
        return table.tolist()
    return [[_number(v) for v in row] for row in table.tolist()]


def _number(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def _atomic_temp_file(target: Path, mode: str) -> IO[Any]:
    target.parent.mkdir(parents=True, exist_ok=True)
    return tempfile.NamedTemporaryFile(
        mode,
        dir=target.parent,
        prefix=f".{target.name}.",
        suffix=".tmp",
        delete=False,
        **({"encoding": "utf-8", "newline": ""} if "b" not in mode else {}),
    )


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _commit_file(handle: IO[Any], target: Path) -> None:
    """Flush, give the usual permissions (temporary files are private) and move into place."""
    handle.flush()
    os.fsync(handle.fileno())
    handle.close()
    os.chmod(handle.name, 0o666 & ~_umask())
    os.replace(handle.name, target)


def _discard_file(handle: IO[Any]) -> None:
    handle.close()
    Path(handle.name).unlink(missing_ok=True)


def _write_json_atomically(target: Path, content: Mapping[str, Any]) -> None:
    write_text_atomically(target, json.dumps(content, indent=2, allow_nan=False) + "\n")


def write_text_atomically(target: str | Path, text: str) -> Path:
    """Write ``text`` to ``target`` so that it appears complete or not at all."""
    target = Path(target)
    handle = _atomic_temp_file(target, "w")
    try:
        handle.write(text)
        _commit_file(handle, target)
    except BaseException:
        _discard_file(handle)
        raise
    return target


class ResultWriter(ABC):
    """Base of the writers: a context manager with :meth:`write`.

    Parameters
    ----------
    path:
        Output path.
    meta:
        Caller metadata for ``.meta.json`` (``input``, ``method``, ``params``,
        ``reader``, ``counts``...).
    frame:
        ``"sensor"`` (as extracted) or ``"world"`` (moved by ``scan.pose``).
    """

    format_name: ClassVar[str] = "result"

    def __init__(
        self, path: str | Path, *, meta: Mapping[str, Any] | None = None, frame: Frame = "sensor"
    ) -> None:
        if frame not in ("sensor", "world"):
            raise ParameterError(f"frame must be 'sensor' or 'world', got {frame!r}")
        self.path = Path(path)
        self.frame: Frame = frame
        self.meta: dict[str, Any] = dict(meta or {})
        self.counts = {"scans": 0, "segments": 0, "breakpoints": 0, "corners": 0}
        self._first_extraction: Extraction | None = None
        self._closed = False

    # -- public API -----------------------------------------------------------------------

    def write(self, index: int, scan: Scan, extraction: Extraction) -> None:
        """Write the features of one scan.

        Parameters
        ----------
        index:
            The scan's record index in the log (``reader.enumerate()``).
        scan:
            The scan the features were extracted from.
        extraction:
            The features, in the sensor frame.
        """
        if self._closed:
            raise ValueError(f"{self.path}: writer is closed")
        features = _features(index, scan, extraction, self.frame)
        self._write(features)
        if self._first_extraction is None:
            self._first_extraction = extraction
        self.counts["scans"] += 1
        self.counts["segments"] += len(extraction)
        self.counts["breakpoints"] += len(extraction.breakpoints)
        self.counts["corners"] += len(extraction.corners)

    def update_meta(self, **fields: Any) -> None:
        """Add or replace ``.meta.json`` fields before closing; ``counts`` are merged."""
        counts = fields.pop("counts", None)
        self.meta.update(fields)
        if counts:
            self.meta["counts"] = {**self.meta.get("counts", {}), **counts}

    @property
    def meta_path(self) -> Path:
        """Where the ``.meta.json`` goes."""
        return meta_path_for(self.path)

    def close(self) -> None:
        """Finish: move the output into place and write the ``.meta.json``."""
        if self._closed:
            return
        self._closed = True
        try:
            self._commit()
        except BaseException:
            self._abort()
            raise
        _write_json_atomically(self.meta_path, self._meta_document())

    def abort(self) -> None:
        """Discard everything written; no output is left."""
        if self._closed:
            return
        self._closed = True
        self._abort()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    # -- format hooks ---------------------------------------------------------------------

    @abstractmethod
    def _write(self, features: ScanFeatures) -> None:
        """Write one scan's features to the temporary output."""

    @abstractmethod
    def _commit(self) -> None:
        """Move the temporary output into place."""

    @abstractmethod
    def _abort(self) -> None:
        """Delete the temporary output."""

    # -- metadata -------------------------------------------------------------------------

    def _meta_document(self) -> dict[str, Any]:
        from scanlines import __version__

        meta = dict(self.meta)
        first = self._first_extraction
        if first is not None:
            meta.setdefault("method", first.method)
            meta.setdefault("params", dict(first.params))
        counts = {**meta.pop("counts", {}), **self.counts}
        document = {
            "format_version": META_FORMAT_VERSION,
            "scanlines_version": __version__,
            "output": self.path.name,
            "output_format": self.format_name,
            "frame": self.frame,
            "input": None,
            "method": None,
            "params": None,
            **meta,
            "counts": counts,
        }
        return jsonable(document)


class _TextFileWriter(ResultWriter):
    """Shared atomic temp-file handling of the text writers."""

    def __init__(
        self, path: str | Path, *, meta: Mapping[str, Any] | None = None, frame: Frame = "sensor"
    ) -> None:
        super().__init__(path, meta=meta, frame=frame)
        if self.path.is_dir():
            raise ParameterError(f"{self.path} is a directory")
        self._handle = _atomic_temp_file(self.path, "w")

    def _commit(self) -> None:
        _commit_file(self._handle, self.path)

    def _abort(self) -> None:
        _discard_file(self._handle)


class JsonlWriter(_TextFileWriter):
    """One JSON object per written scan (see the module docstring)."""

    format_name = "jsonl"

    def _write(self, features: ScanFeatures) -> None:
        self._handle.write(json_record(features))
        self._handle.write("\n")


class CsvWriter(_TextFileWriter):
    """One CSV row per segment (see the module docstring)."""

    format_name = "csv"

    def __init__(
        self, path: str | Path, *, meta: Mapping[str, Any] | None = None, frame: Frame = "sensor"
    ) -> None:
        super().__init__(path, meta=meta, frame=frame)
        self._csv = csv.writer(self._handle, lineterminator="\n")
        self._csv.writerow(CSV_COLUMNS)

    def _write(self, features: ScanFeatures) -> None:
        extraction = features.extraction
        stamp = _cell(features.scan.timestamp)
        for k, row in enumerate(extraction.lines):
            covariance = extraction.covariances[k]
            start_kind, end_kind = extraction.end_kinds[k]
            self._csv.writerow(
                (
                    features.index,
                    stamp,
                    int(extraction.first[k]),
                    int(extraction.last[k]),
                    _cell(row[START_X]),
                    _cell(row[START_Y]),
                    _cell(row[END_X]),
                    _cell(row[END_Y]),
                    _cell(row[0]),
                    _cell(row[1]),
                    int(extraction.n_points[k]),
                    _cell(row[6]),
                    _cell(covariance[0, 0]),
                    _cell(covariance[0, 1]),
                    _cell(covariance[1, 1]),
                    END_KINDS[start_kind],
                    END_KINDS[end_kind],
                )
            )


def _cell(value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return ""
    return repr(float(value))


# -- ROS 2 ---------------------------------------------------------------------------------
