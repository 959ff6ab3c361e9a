"""Reading 2D laser logs and writing extraction results.

Reading
-------
:func:`open_log` returns a reader for any supported log; a reader is a
re-iterable stream of :class:`~scanlines.Scan` (each iteration re-opens the
file and holds one record at a time)::

    from scanlines.io import open_log
    reader = open_log("intel.clf.gz")                  # format from name + content
    reader = open_log("run.bag", topic="/front/scan")  # reader options as keywords
    reader = open_log("run.bag", options=ReaderOptions(topic="/front/scan"))  # or as one
    for index, scan in reader.enumerate():             # index = record number in the log
        ...
    reader.info()        # format, options, records/skipped/error counts of the last pass

==========  ==========================================  ==============================
format      files                                       module
==========  ==========================================  ==============================
carmen      ``.log``, ``.clf`` (``.gz``)                :mod:`scanlines.io.carmen`
rosbag      ``.bag``, ROS 2 bag dir, ``.db3``, ``.mcap``  :mod:`scanlines.io.rosbag`
coreslam    ``.dat`` (``.gz``)                          :mod:`scanlines.io.coreslam`
csv         ``.csv`` (``.gz``), one scan per row        :mod:`scanlines.io.tabular`
npz         ``.npz`` stack of scans                     :mod:`scanlines.io.npz`
==========  ==========================================  ==============================

Each module's docstring gives its layout, the options, where ``timestamp`` and
``pose`` come from and how "no return" beams are recognised. Every reader
takes ``on_error="fail"`` (raise :class:`~scanlines.LogFormatError` naming
file, line and field) or ``"skip"`` (drop and count malformed records: see
:mod:`scanlines.io.base`).

Writing
-------
:func:`open_writer` writes ``.jsonl``, ``.csv``, ``.mcap``, a ROS 2 bag
directory or a Rerun recording (``.rrd``), atomically, with ``<output>.meta.json``
beside it (see :mod:`scanlines.io.writers`)::

    with open_writer("out.jsonl", meta={"input": str(path)}) as writer:
        for index, scan in reader.enumerate():
            writer.write(index, scan, extract(scan))

:func:`to_world` moves an extraction into the log's world frame.

``import scanlines.io`` needs only numpy; rosbags is imported when a bag is
read or written, the Rerun SDK when a ``.rrd`` is written.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from scanlines.errors import ParameterError
from scanlines.geometry.transform import points_to_world, to_world
from scanlines.io.bag_writer import Ros2BagWriter
from scanlines.io.base import LogReader
from scanlines.io.carmen import CarmenReader
from scanlines.io.coreslam import CoreSlamReader
from scanlines.io.detect import FORMAT_DESCRIPTIONS, detect_format
from scanlines.io.npz import NpzReader
from scanlines.io.rerun_writer import RerunWriter
from scanlines.io.rosbag import RosbagReader
from scanlines.io.tabular import CsvReader
from scanlines.io.writers import (
    CSV_COLUMNS,
    CsvWriter,
    Frame,
    JsonlWriter,
    ResultWriter,
    meta_path_for,
)
from scanlines.reader_options import ReaderOptions

__all__ = [
    "CSV_COLUMNS",
    "FORMAT_DESCRIPTIONS",
    "READERS",
    "CarmenReader",
    "CoreSlamReader",
    "CsvReader",
    "CsvWriter",
    "JsonlWriter",
    "LogReader",
    "NpzReader",
    "ReaderOptions",
    "RerunWriter",
    "ResultWriter",
    "Ros2BagWriter",
    "RosbagReader",
    "detect_format",
    "meta_path_for",
    "open_log",
    "open_writer",
    "points_to_world",
    "reader_option_names",
    "to_world",
    "writer_class",
]

#: Format name -> reader class.
READERS: dict[str, type[LogReader]] = {
    "carmen": CarmenReader,
    "rosbag": RosbagReader,
    "coreslam": CoreSlamReader,
    "csv": CsvReader,
    "npz": NpzReader,
}


def reader_option_names(format_name: str) -> list[str]:
    """The keyword options the reader of ``format_name`` accepts."""
    cls = READERS[format_name]
    parameters = inspect.signature(cls.__init__).parameters.values()
    return [p.name for p in parameters if p.kind is inspect.Parameter.KEYWORD_ONLY]


def open_log(
    path: str | Path,
    *,
    format: str | None = None,
    options: ReaderOptions | Mapping[str, Any] | None = None,
    **keywords: Any,
) -> LogReader:
    """Open a laser log for streaming, choosing the reader by name and content.

    Parameters
    ----------
    path:
        Log file, or ROS 2 bag directory.
    format:
        Force a reader (a key of :data:`READERS`) instead of detecting it.
    options, **keywords:
        Options of that reader (see :func:`reader_option_names`), as a
        :class:`ReaderOptions` (or a mapping of its names) and as keywords (these
        win), e.g. ``fov``, ``angle_convention``, ``max_range`` (CARMEN), ``topic``
        (bags), ``angle_min``/``angle_increment`` (CSV), ``on_error`` (all).

    Returns
    -------
    LogReader
        Iterate it for :class:`~scanlines.Scan` objects, or call ``enumerate()``.

    Raises
    ------
    LogFormatError
        Unknown format, empty or truncated file, content contradicting the
        name, a bag without (or with several) ``LaserScan`` topics... The
        message names the file.
    ParameterError
        An option that the chosen reader does not take, or a bad option value.
    """
    path = Path(path)
    if format is None:
        format = detect_format(path)
    elif format not in READERS:
        raise ParameterError(f"unknown format {format!r}; formats: {', '.join(READERS)}")
    given = {**ReaderOptions.of(options).given(), **keywords}
    accepted = reader_option_names(format)
    unknown = sorted(set(given) - set(accepted))
    if unknown:
        raise ParameterError(
            f"{path}: option(s) {', '.join(unknown)} do not apply to {format} logs; "
            f"{format} options: {', '.join(accepted)}"
        )
    return READERS[format](path, **given)


#: Output suffix -> writer class (a path without suffix: a ROS 2 bag directory).
WRITERS: dict[str, type[ResultWriter]] = {
    ".jsonl": JsonlWriter,
    ".csv": CsvWriter,
    ".mcap": Ros2BagWriter,
    ".rrd": RerunWriter,
}


def writer_class(path: str | Path) -> type[ResultWriter]:
    """The writer of an output path, by its suffix (checked before any work is done).

    Raises
    ------
    ParameterError
        For a suffix no writer has.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in WRITERS:
        return WRITERS[suffix]
    if suffix == "" or (path.is_dir() and (path / "metadata.yaml").exists()):
        return Ros2BagWriter
    raise ParameterError(
        f"{path}: unknown output format {suffix!r}; use .jsonl, .csv, .mcap, .rrd or a "
        f"directory path without suffix (ROS 2 bag)"
    )


def open_writer(
    path: str | Path,
    *,
    meta: Mapping[str, Any] | None = None,
    frame: Frame = "sensor",
    overwrite: bool = False,
    **options: Any,
) -> ResultWriter:
    """Open a result writer, choosing the format from the path.

    Parameters
    ----------
    path:
        ``*.jsonl``, ``*.csv``, ``*.mcap``, ``*.rrd`` (Rerun), or a path without
        suffix (or an existing ROS 2 bag directory) for a ROS 2 bag directory.
    meta:
        Metadata for ``<path>.meta.json``: typically ``input``, ``method``,
        ``params``, ``reader`` (the reader's :meth:`~scanlines.io.base.LogReader.options`).
    frame:
        ``"sensor"`` or ``"world"`` (see the module docstring).
    overwrite:
        Replace an existing output and its ``.meta.json``; without it an existing
        one is an :class:`~scanlines.outputs.OutputError` before anything is
        written (as is a folder that does not exist).
    **options:
        Format options (``Ros2BagWriter``: ``storage``, ``topic``,
        ``markers_topic``, ``laser_frame``, ``world_frame``).

    Returns
    -------
    ResultWriter
        A context manager; call ``write(index, scan, extraction)`` per scan.

    Examples
    --------
    >>> with open_log("run.clf") as reader, open_writer("out.jsonl") as writer:  # doctest: +SKIP
    ...     for index, scan in reader.enumerate():
    ...         writer.write(index, scan, extract(scan))
    ...     writer.update_meta(counts={"skipped_scan_records": reader.bad_scans})
    """
    path = Path(path)
    cls = writer_class(path)
    if options and cls is not Ros2BagWriter:
        raise ParameterError(f"{path}: options {sorted(options)} apply only to ROS 2 bag output")
    return cls(path, meta=meta, frame=frame, overwrite=overwrite, **options)
