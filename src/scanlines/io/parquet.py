"""Features as a Parquet dataset: three tables, partitioned by log, for DuckDB, pandas, polars.

Layout of a dataset folder::

    DATASET/segments/log=NAME/part-FIRST.parquet   one row per segment
    DATASET/events/log=NAME/part-FIRST.parquet     one row per breakpoint or corner
    DATASET/scans/log=NAME/part-FIRST.parquet      one row per scan
    DATASET/_logs/NAME.json                        what made a log's rows (see scanlines.runs.fleet)
    DATASET/_staging/TABLE/log=NAME/part-*.parquet the parts of a log not done yet

``FIRST`` is the first scan record of the part (zero-padded), so a part written again
(a retried task) replaces itself: no row is ever written twice. A fleet run writes a log's
parts under ``_staging`` and moves them into the tables (:func:`commit_log`) only once the
log is done, so a query of ``DATASET/segments/*/*.parquet`` never sees an unfinished log.
Every file carries the package version, the method and its resolved parameters in its
schema metadata (key ``scanlines``). Columns:

* ``segments``: ``scan`` (record index in the log), ``segment`` (its order in the scan),
  ``timestamp``, ``method``, ``first``, ``last``, ``n_points``, ``rho``, ``alpha``,
  ``start_x``, ``start_y``, ``end_x``, ``end_y``, ``rms``, ``var_rho``,
  ``cov_rho_alpha``, ``var_alpha``, ``start_kind``, ``end_kind``;
* ``events``: ``scan``, ``kind`` (``breakpoint`` or ``corner``), ``beam``, ``x``, ``y``
  (the beam's point in the sensor frame; null without a return);
* ``scans``: ``scan``, ``timestamp``, ``pose_x``, ``pose_y``, ``pose_theta``, ``beams``,
  ``segments``, ``breakpoints``, ``corners``.

The ``log`` column comes from the partition folder (hive partitioning): DuckDB reads it as
``read_parquet('DATASET/segments/*/*.parquet', hive_partitioning = true)``.

pyarrow is imported here only: the ``fleet`` extra brings it (``pip install ".[fleet]"`` in a
checkout of the repository).
"""

from __future__ import annotations

import contextlib
import json
import math
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError, describe
from scanlines.extraction import (
    ALPHA,
    END_KINDS,
    END_X,
    END_Y,
    RHO,
    RMS,
    START_X,
    START_Y,
    ExtractionTable,
)
from scanlines.outputs import OutputError, commit, discard, temp_path
from scanlines.scan import Scan

__all__ = [
    "STAGING",
    "TABLES",
    "commit_log",
    "discard_staged",
    "part_name",
    "remove_empty_folders",
    "remove_log",
    "require_pyarrow",
    "write_parts",
]

#: The dataset's tables.
TABLES = ("segments", "events", "scans")
#: The folder of a dataset holding the parts of logs not done yet.
STAGING = "_staging"


def require_pyarrow() -> Any:
    """``pyarrow`` and ``pyarrow.parquet``, or a one-line error naming the extra."""
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        raise ParameterError(
            'Parquet output needs pyarrow: pip install ".[fleet]" in a scanlines checkout'
        ) from None
    return pyarrow


def part_name(first_record: int) -> str:
    """The file name of the part whose first scan record is ``first_record``."""
    return f"part-{first_record:010d}.parquet"


def write_parts(
    dataset: Path,
    log: str,
    first_record: int,
    indices: Sequence[int],
    scans: Sequence[Scan],
    table: ExtractionTable,
    *,
    staged: bool = False,
) -> dict[str, int]:
    """Write the three tables of one chunk of a log's scans; return rows per table.

    Each file appears whole or not at all and replaces a part of the same name (a
    retried task writes the same rows again). ``staged``: under ``_staging``, out of the
    tables' sight until :func:`commit_log`."""
    pa = require_pyarrow()
    metadata = {
        b"scanlines": json.dumps(
            {"version": _version(), "method": table.method, "params": _jsonable(table.params)}
        ).encode()
    }
    tables = {
        "segments": _segments(pa, indices, scans, table),
        "events": _events(pa, indices, scans, table),
        "scans": _scans(pa, indices, scans, table),
    }
    root = dataset / STAGING if staged else dataset
    for name, columns in tables.items():
        folder = root / name / f"log={log}"
        folder.mkdir(parents=True, exist_ok=True)
        _write_atomically(pa, folder / part_name(first_record), columns, metadata)
    return {name: columns.num_rows for name, columns in tables.items()}


def _write_atomically(pa: Any, target: Path, columns: Any, metadata: dict) -> None:
    import pyarrow.parquet as pq

    temporary = temp_path(target)
    try:
        pq.write_table(columns.replace_schema_metadata(metadata), temporary)
        commit([(temporary, target)], overwrite=True)
    except OutputError:
        raise
    except OSError as exc:  # a full disk, a file size limit: name the part
        raise OutputError(f"{target}: cannot write the part ({describe(exc)})") from None
    finally:
        discard(temporary)


def _segments(pa: Any, indices, scans, table: ExtractionTable) -> Any:
    owner = table.segment_scan
    order = np.arange(len(owner)) - table.offsets["segments"][owner]
    scan_index = np.asarray(indices, dtype=np.int64)[owner]
    stamps = np.array([_stamp(s) for s in scans], dtype=np.float64)[owner]
    lines, cov = table.lines, table.covariances.reshape(-1, 4)
    kinds = np.asarray(END_KINDS, dtype=object)
    return pa.table(
        {
            "scan": scan_index,
            "segment": order.astype(np.int32),
            "timestamp": pa.array(stamps, mask=np.isnan(stamps)),
            "method": pa.array([table.method] * len(owner), pa.string()).dictionary_encode(),
            "first": table.first.astype(np.int64),
            "last": table.last.astype(np.int64),
            "n_points": table.n_points.astype(np.int64),
            "rho": lines[:, RHO],
            "alpha": lines[:, ALPHA],
            "start_x": lines[:, START_X],
            "start_y": lines[:, START_Y],
            "end_x": lines[:, END_X],
            "end_y": lines[:, END_Y],
            "rms": lines[:, RMS],
            "var_rho": cov[:, 0],
            "cov_rho_alpha": cov[:, 1],
            "var_alpha": cov[:, 3],
            "start_kind": pa.array(kinds[table.end_kinds[:, 0]].tolist(), pa.string()),
            "end_kind": pa.array(kinds[table.end_kinds[:, 1]].tolist(), pa.string()),
        }
    )


def _events(pa: Any, indices, scans, table: ExtractionTable) -> Any:
    from scanlines.io.feature_records import beam_xy

    parts = []
    for kind in ("breakpoints", "corners"):
        owner = np.repeat(np.arange(len(table)), table.counts(kind))
        offsets = table.offsets[kind]
        beams = table.columns[kind]
        xy = [beam_xy(scan, beams[offsets[k] : offsets[k + 1]]) for k, scan in enumerate(scans)]
        points = np.concatenate(xy) if xy else np.zeros((0, 2))
        parts.append((np.asarray(indices, dtype=np.int64)[owner], kind[:-1], beams, points))
    points = np.concatenate([p for *_, p in parts])
    missing = np.isnan(points[:, 0])
    return pa.table(
        {
            "scan": np.concatenate([scan for scan, *_ in parts]),
            "kind": pa.array(
                [kind for scan, kind, *_ in parts for _ in range(len(scan))], pa.string()
            ),
            "beam": np.concatenate([beams for _, _, beams, _ in parts]).astype(np.int64),
            "x": pa.array(points[:, 0], pa.float64(), mask=missing),
            "y": pa.array(points[:, 1], pa.float64(), mask=missing),
        }
    )


def _scans(pa: Any, indices, scans, table: ExtractionTable) -> Any:
    poses = np.array([s.pose if s.pose is not None else (math.nan,) * 3 for s in scans])
    stamps = np.array([_stamp(s) for s in scans], dtype=np.float64)
    missing = np.isnan(poses[:, 0]) if len(scans) else np.zeros(0, dtype=bool)
    return pa.table(
        {
            "scan": np.asarray(indices, dtype=np.int64),
            "timestamp": pa.array(stamps, mask=np.isnan(stamps)),
            "pose_x": pa.array(poses[:, 0] if len(scans) else [], pa.float64(), mask=missing),
            "pose_y": pa.array(poses[:, 1] if len(scans) else [], pa.float64(), mask=missing),
            "pose_theta": pa.array(poses[:, 2] if len(scans) else [], pa.float64(), mask=missing),
            "beams": np.array([len(s) for s in scans], dtype=np.int64),
            "segments": table.counts("segments").astype(np.int64),
            "breakpoints": table.counts("breakpoints").astype(np.int64),
            "corners": table.counts("corners").astype(np.int64),
        }
    )


def _stamp(scan: Scan) -> float:
    return math.nan if scan.timestamp is None else float(scan.timestamp)


def _version() -> str:
    from scanlines import __version__

    return __version__


def _jsonable(values: Any) -> Any:
    from scanlines.report import jsonable

    return jsonable(values)


def commit_log(dataset: Path, log: str) -> None:
    """Move the staged parts of ``log`` into the tables, replacing its rows there (a folder
    rename per table)."""
    for name in TABLES:
        staged = dataset / STAGING / name / f"log={log}"
        target = dataset / name / f"log={log}"
        if not staged.is_dir():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.rmtree(target, ignore_errors=True)
        staged.rename(target)
    for folder in [*(dataset / STAGING / name for name in TABLES), dataset / STAGING]:
        with contextlib.suppress(OSError):  # only when empty: other logs may be staged
            folder.rmdir()


def remove_empty_folders(dataset: Path) -> None:
    """Remove the dataset's table, staging and ``_logs`` folders that hold nothing (left
    by failed or moved logs)."""
    folders = [dataset / STAGING / name for name in TABLES] + [dataset / STAGING]
    folders += [dataset / name for name in TABLES] + [dataset / "_logs"]
    for folder in folders:
        with contextlib.suppress(OSError):  # not there, or not empty
            folder.rmdir()


def discard_staged(dataset: Path, log: str) -> None:
    """Delete the staged parts of ``log`` (those of an interrupted run)."""
    for name in TABLES:
        shutil.rmtree(dataset / STAGING / name / f"log={log}", ignore_errors=True)


def remove_log(dataset: Path, log: str) -> None:
    """Delete every part of ``log``, staged or not (a failed or replaced log leaves no rows
    behind)."""
    for name in TABLES:
        shutil.rmtree(dataset / name / f"log={log}", ignore_errors=True)
        shutil.rmtree(dataset / STAGING / name / f"log={log}", ignore_errors=True)
    remove_empty_folders(dataset)
    (dataset / "_logs" / f"{log}.json").unlink(missing_ok=True)
    (dataset / "_logs" / f"{log}.pending.json").unlink(missing_ok=True)
