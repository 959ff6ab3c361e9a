"""Writing extraction results: JSON Lines, CSV, ROS 2 bags with markers, Rerun.

Use :func:`scanlines.io.open_writer`; it picks the format from the output path
(the ROS 2 writer is :mod:`scanlines.io.bag_writer`, the Rerun writer
:mod:`scanlines.io.rerun_writer`):

============================  =================================================
``*.jsonl``                   one JSON object per written scan
``*.csv``                     one row per segment
``*.mcap``                    a single MCAP file (ROS 2 messages)
``*.rrd``                     a Rerun recording (entities and timelines: see
                              :mod:`scanlines.io.rerun_writer`)
a path without suffix         a ROS 2 bag directory (``storage="mcap"`` or
                              ``"sqlite3"``)
============================  =================================================

Every writer streams (one scan in memory at a time) and is atomic: output
goes to a hidden temporary file or directory next to the target
(``.<name>.<process id>.<random>.tmp``) and is moved into place together with
its ``.meta.json``, both or neither, only when the writer is closed without
error (:mod:`scanlines.outputs`); an exception inside the ``with`` block
(or :meth:`ResultWriter.abort`) deletes it. A writer refuses, before writing
anything, a target in a folder that does not exist, and an existing target
(or ``.meta.json``) unless ``overwrite=True``.

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
:func:`scanlines.geometry.transform.to_world`) and breakpoint/corner points into the
log's world frame using ``scan.pose``; a scan without a pose is then an error.
Do not transform beforehand as well.

Record layouts
--------------
JSON Lines: ``{"scan", "timestamp", "pose", "segments": [{"first", "last",
"start", "end", "rho", "alpha", "n_points", "rms", "covariance", "start_kind",
"end_kind"}], "breakpoints", "corners", "breakpoint_xy", "corner_xy"}``, where ``scan``
is the record index in the log, breakpoints and corners are beam indices and
``breakpoint_xy``/``corner_xy`` their points ``[x, y]`` in the output frame, in the same
order (``[null, null]`` for a beam without a return), ``covariance`` is the 2 x 2
covariance of ``(rho, alpha)`` as ``[[var_rho, cov], [cov, var_alpha]]``, the kinds
say what ends the segment (:data:`scanlines.extraction.END_KINDS`), and missing or
non-finite numbers are ``null``.

CSV columns: ``scan,timestamp,first,last,start_x,start_y,end_x,end_y,rho,alpha,n_points,rms,
var_rho,cov_rho_alpha,var_alpha,start_kind,end_kind,pose_x,pose_y,pose_theta,feature,beam,x,y``.
Per scan, one row per segment (``feature`` ``segment``, ``beam``, ``x``, ``y`` empty), then
one per breakpoint and per corner (``feature`` ``breakpoint`` or ``corner``, the beam and
its point in the output frame, the segment cells empty); the scan's pose on every row;
missing or non-finite values are empty cells. A scan without features writes no row.

ROS 2 (``rosbags.rosbag2.Writer``, ``Stores.ROS2_HUMBLE`` types), per scan,
stamped with the scan time (``index * 0.1`` s when the scan has none):

* the input scan as ``sensor_msgs/msg/LaserScan`` on ``topic`` (``/scan``),
  frame ``laser_frame`` (``"laser"``), ranges unchanged as float32;
* a ``visualization_msgs/msg/MarkerArray`` on ``/scanlines/markers``: a
  ``DELETEALL`` marker, then (only when non-empty) namespace ``segments``
  (``LINE_LIST``, green, two points per segment), ``breakpoints``
  (``SPHERE_LIST``, red) and ``corners`` (``SPHERE_LIST``, blue), in frame
  ``laser_frame`` or, with ``frame="world"``, ``world_frame`` (``"map"``);
* the scan's features as the project's typed ``scanlines/msg/ScanFeatures`` on
  ``/scanlines/scan_features`` (every segment with its covariance and end kinds, the
  breakpoints', corners' and outliers' beams, the breakpoints and corners as points, in
  the markers' frame; :mod:`scanlines.io.feature_messages`): the bag and the MCAP
  schema carry its definition, so Foxglove and rosbags decode, plot and filter it;
* the scan's JSON Lines record (above) as ``std_msgs/msg/String`` on
  ``/scanlines/features``, as before;
* when the scan has a pose, a ``tf2_msgs/msg/TFMessage`` on ``/tf`` from
  ``world_frame`` to ``laser_frame``, so Foxglove/RViz can place the scan.

Bag readers return messages in time order, so scans whose timestamps go
backwards (the Intel raw log) come back sorted by time from the bag. The
``.mcap`` file and the bag directory get the usual permissions (``0o666``
less the umask); so do the text outputs, the ``.rrd`` file and the ``.meta.json``.

Rerun: per scan, the returns, segments, breakpoints, corners and outliers on the
timelines ``scan`` and ``time`` (:mod:`scanlines.io.rerun_writer`).
"""

from __future__ import annotations

import json
import os
from abc import ABC, abstractmethod
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import Any, ClassVar, Self

from scanlines.errors import ParameterError
from scanlines.extraction import (
    Extraction,
    ExtractionTable,
)
from scanlines.io.feature_records import (
    CSV_COLUMNS,
    Frame,
    ScanFeatures,
    beam_xy,
    encode_csv_rows,
    encode_json_lines,
    json_record,
    json_records,
)
from scanlines.outputs import (
    OutputError,
    check_output,
    commit,
    discard,
    temp_path,
    umask,
    write_error,
)
from scanlines.report import jsonable
from scanlines.scan import Scan

__all__ = [
    "CSV_COLUMNS",
    "META_FORMAT_VERSION",
    "CsvWriter",
    "Frame",
    "JsonlWriter",
    "ResultWriter",
    "ScanFeatures",
    "beam_xy",
    "encode_csv_rows",
    "encode_json_lines",
    "json_record",
    "json_records",
    "meta_path_for",
]

#: Version of the ``.meta.json`` layout.
META_FORMAT_VERSION = 1
#: Bag time step used for scans without a timestamp (seconds per record index).
UNSTAMPED_PERIOD = 0.1


def meta_path_for(path: str | Path) -> Path:
    """The ``.meta.json`` written beside ``path``: ``<path>.meta.json``."""
    path = Path(path)
    return path.with_name(path.name + ".meta.json")


def _write_json(path: Path, content: Mapping[str, Any]) -> None:
    with open(path, "x", encoding="utf-8") as handle:
        handle.write(json.dumps(content, indent=2, allow_nan=False) + "\n")
        handle.flush()
        os.fsync(handle.fileno())
    os.chmod(path, 0o666 & ~umask())


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
    overwrite:
        Replace an existing output and its ``.meta.json``.
    """

    format_name: ClassVar[str] = "result"

    def __init__(
        self,
        path: str | Path,
        *,
        meta: Mapping[str, Any] | None = None,
        frame: Frame = "sensor",
        overwrite: bool = False,
    ) -> None:
        if frame not in ("sensor", "world"):
            raise ParameterError(f"frame must be 'sensor' or 'world', got {frame!r}")
        self.path = Path(path)
        self.overwrite = overwrite
        check_output(self.path, overwrite=overwrite, companions=[meta_path_for(self.path)])
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
        self._check_open()
        with self._naming_the_output():
            self._write(ScanFeatures(index, scan, extraction, self.frame))
        self._count(extraction, 1, len(extraction), extraction.breakpoints, extraction.corners)

    def encode_chunk(
        self, indices: Sequence[int], scans: Sequence[Scan], table: ExtractionTable
    ) -> Any:
        """The output of a chunk of scans, ready for :meth:`write_chunk` (or ``None``: the
        format writes scan by scan). Safe to call from several threads at once: it reads
        the writer's settings and changes nothing."""
        return None

    def write_chunk(
        self,
        indices: Sequence[int],
        scans: Sequence[Scan],
        table: ExtractionTable,
        encoded: Any = None,
    ) -> None:
        """Write the features of a chunk of scans (``table[k]`` those of ``scans[k]``), in
        order, from :meth:`encode_chunk`'s result when given."""
        self._check_open()
        if encoded is None:
            for index, scan, extraction in zip(indices, scans, table, strict=True):
                self.write(index, scan, extraction)
            return
        with self._naming_the_output():
            self._write_encoded(encoded)
        first = table[0] if len(table) else None
        self._count(first, len(table), len(table.first), table.breakpoints, table.corners)

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError(f"{self.path}: writer is closed")

    @contextmanager
    def _naming_the_output(self) -> Iterator[None]:
        """An OS error while writing (a full disk, a file size limit) as an
        :class:`OutputError` naming the output."""
        try:
            yield
        except OutputError:
            raise
        except OSError as exc:
            raise write_error(self.path, exc) from None

    def _count(self, first: Extraction | None, scans: int, segments: int, breakpoints, corners):
        if self._first_extraction is None:
            self._first_extraction = first
        self.counts["scans"] += scans
        self.counts["segments"] += segments
        self.counts["breakpoints"] += len(breakpoints)
        self.counts["corners"] += len(corners)

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
        """Finish: move the output and its ``.meta.json`` into place, together."""
        if self._closed:
            return
        self._closed = True
        meta_temporary = temp_path(self.meta_path)
        try:
            with self._naming_the_output():
                self._finish()
                _write_json(meta_temporary, self._meta_document())
            commit(
                [(self._temporary, self.path), (meta_temporary, self.meta_path)],
                overwrite=self.overwrite,
            )
        except BaseException:
            self._abort()
            discard(meta_temporary)
            raise

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

    def _write_encoded(self, encoded: Any) -> None:
        """Write what :meth:`encode_chunk` returned."""
        raise NotImplementedError

    @property
    @abstractmethod
    def _temporary(self) -> Path:
        """The temporary output (file or folder) that :meth:`close` moves into place."""

    @abstractmethod
    def _finish(self) -> None:
        """Complete the temporary output (flush, close)."""

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
    """Shared atomic temp-file handling of the text writers; a chunk is encoded at once
    (``_encode``: indices, scans, table in the output frame -> text or bytes)."""

    def __init__(
        self,
        path: str | Path,
        *,
        meta: Mapping[str, Any] | None = None,
        frame: Frame = "sensor",
        overwrite: bool = False,
    ) -> None:
        super().__init__(path, meta=meta, frame=frame, overwrite=overwrite)
        if self.path.is_dir():
            raise ParameterError(f"{self.path} is a directory")
        self._temporary_file = temp_path(self.path)
        with self._naming_the_output():  # a read-only folder, say
            self._handle = open(self._temporary_file, "xb")  # noqa: SIM115 - closed by _finish

    def _write(self, features: ScanFeatures) -> None:
        extraction = features.extraction
        table = ExtractionTable.concatenate([extraction], extraction.method, extraction.params)
        self._handle.write(self._encode([features.index], [features.scan], table, self.frame))

    def encode_chunk(self, indices, scans, table) -> str | bytes:
        if self.frame == "world":
            features = [
                ScanFeatures(i, s, e, "world")
                for i, s, e in zip(indices, scans, table, strict=False)
            ]
            table = ExtractionTable.concatenate(
                [f.extraction for f in features], table.method, table.params
            )
        return self._encode(indices, scans, table, self.frame)

    def _write_encoded(self, encoded: str | bytes) -> None:
        self._handle.write(encoded)

    @staticmethod
    def _encode(indices, scans, table, frame) -> str | bytes:
        raise NotImplementedError

    @property
    def _temporary(self) -> Path:
        return self._temporary_file

    def _finish(self) -> None:
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self._handle.close()
        os.chmod(self._temporary_file, 0o666 & ~umask())

    def _abort(self) -> None:
        self._handle.close()
        discard(self._temporary_file)


class JsonlWriter(_TextFileWriter):
    """One JSON object per written scan (see the module docstring)."""

    format_name = "jsonl"
    _encode = staticmethod(encode_json_lines)


class CsvWriter(_TextFileWriter):
    """One CSV row per segment (see the module docstring)."""

    format_name = "csv"
    _encode = staticmethod(encode_csv_rows)

    def __init__(
        self,
        path: str | Path,
        *,
        meta: Mapping[str, Any] | None = None,
        frame: Frame = "sensor",
        overwrite: bool = False,
    ) -> None:
        super().__init__(path, meta=meta, frame=frame, overwrite=overwrite)
        self._handle.write((",".join(CSV_COLUMNS) + "\n").encode())


# -- ROS 2 ---------------------------------------------------------------------------------
