"""Many logs at once: a Parquet dataset of their features, on local processes or a Dask cluster.

The work is a list of :class:`ChunkTask`: one per log, or several for a long log (records
``[start, stop)``, the last one open-ended), each extracting its records and writing them
as one part of each table of the dataset (:mod:`scanlines.io.parquet`). The same tasks
run on a local process pool (``jobs``) or on Dask (``scheduler``: an address, or
``"local"`` for a :class:`distributed.LocalCluster`); :func:`fleet_tasks` gives them as
``dask.delayed`` objects for a notebook with a cluster of its own.

Faults: a log that cannot be read is reported with its reason and the others go on; its
rows are removed. A task whose worker dies is run again by Dask; a part written twice
replaces itself, so no row is lost or doubled. Parts are written under the dataset's
``_staging`` folder and moved into its tables only when every task of their log is done,
so an interrupted run leaves no partial log in sight of a query. When a log is done,
``_logs/NAME.json`` records its input checksum, method, parameters and sensor profile
option: running the same command again skips it; a different one is an error unless
``overwrite``.

Every chunk of a log measures the log's sensor profile from the log's first scans (as
``scanlines run`` does), so the rows are those of a single-log run, bit for bit.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import json
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from scanlines.builtin_methods import DEFAULT_METHOD
from scanlines.errors import ParameterError, ScanlinesError, describe
from scanlines.reader_options import ReaderOptions

# dask_setup: the Dask workers' preload is this module (see executors._executor)
from scanlines.runs.executors import _executor
from scanlines.runs.executors import dask_setup as dask_setup
from scanlines.runs.inputs import estimated_records, expand_inputs, log_names

__all__ = [
    "CHUNK_RECORDS",
    "ChunkTask",
    "FleetSummary",
    "LogOutcome",
    "commit_chunks",
    "expand_inputs",
    "extract_task",
    "fleet_tasks",
    "plan",
    "run_fleet",
]

#: Scan records per task: a longer log is split into chunks of this many.
CHUNK_RECORDS = 5000


@dataclass(frozen=True)
class ChunkTask:
    """The records ``[start, stop)`` of one log (``stop=None``: to the end), extracted
    and written to ``dataset``."""

    log: str
    path: str
    dataset: str
    start: int
    stop: int | None
    method: str
    preset: str | None
    params: dict[str, Any]
    reader_options: ReaderOptions
    sensor_profile: str | None = None
    staged: bool = True  # written under _staging until the log is committed


@dataclass
class ChunkResult:
    log: str
    start: int
    scans: int
    segments: int
    skipped_scans: int | None
    seconds: float
    peak_mb: float = 0.0  # the worker process's peak resident memory so far
    worker: int = 0  # its process id


@dataclass
class LogOutcome:
    """One log of a fleet run: what was written, or why it failed or was skipped."""

    log: str
    path: str
    status: str = "done"  # done | skipped (already done) | failed
    reason: str = ""
    scans: int = 0
    segments: int = 0
    skipped_scans: int = 0
    seconds: float = 0.0
    chunks: int = 0
    peak_mb: float = 0.0


@dataclass
class FleetSummary:
    """Per log outcomes and the totals of a fleet run; ``worker_peak_mb``: each worker
    process's peak resident memory, as its last task saw it."""

    logs: list[LogOutcome] = field(default_factory=list)
    seconds: float = 0.0
    engine: str = ""
    worker_peak_mb: dict[int, float] = field(default_factory=dict)

    @property
    def failed(self) -> list[LogOutcome]:
        return [log for log in self.logs if log.status == "failed"]

    @property
    def scans(self) -> int:
        return sum(log.scans for log in self.logs)

    def to_dict(self) -> dict[str, Any]:
        return {"engine": self.engine, "seconds": self.seconds,
                "logs": [asdict(log) for log in self.logs]}  # fmt: skip


# -- inputs and plan ----------------------------------------------------------------------


def plan(
    paths: Sequence[Path],
    dataset: Path,
    *,
    method: str = DEFAULT_METHOD,
    preset: str | None = None,
    params: dict[str, Any] | None = None,
    reader_options: ReaderOptions | Mapping[str, Any] | None = None,
    sensor_profile: str | None = None,
    chunk_records: int = CHUNK_RECORDS,
) -> tuple[list[ChunkTask], list[LogOutcome]]:
    """The tasks of ``paths`` (records split in chunks of ``chunk_records``), and the
    logs that failed already (unreadable)."""
    tasks, failed = [], []
    for name, path in zip(log_names(paths), paths, strict=True):
        try:
            records = estimated_records(path, ReaderOptions.of(reader_options))
        except (ScanlinesError, OSError) as error:
            failed.append(LogOutcome(name, str(path), "failed", str(error)))
            continue
        starts = list(range(0, max(records, 1), chunk_records))
        for k, start in enumerate(starts):
            stop = starts[k + 1] if k + 1 < len(starts) else None
            tasks.append(
                ChunkTask(name, str(path), str(dataset), start, stop, method, preset,
                          dict(params or {}), ReaderOptions.of(reader_options), sensor_profile)
            )  # fmt: skip
    return tasks, failed


# -- one task -----------------------------------------------------------------------------


def extract_task(task: ChunkTask) -> ChunkResult:
    """Extract the task's records and write them as one part of each table."""
    import os
    import resource

    from scanlines.extraction import ExtractionTable
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.io.parquet import write_parts
    from scanlines.runs.runner import CHUNK_SCANS, chunk_scans, select
    from scanlines.runs.runner import extract_chunk as extract_piece

    started = time.perf_counter()
    profile = _task_profile(task)
    extractor = Extractor(task.method, task.preset, sensor_profile=profile, **task.params)
    indices, scans, tables = [], [], []
    with open_log(task.path, options=task.reader_options) as reader:
        selected = select(reader.enumerate(), slice(task.start, task.stop))
        for piece in chunk_scans(selected, CHUNK_SCANS):
            tables.append(extract_piece(piece, extractor).table)
            indices += piece.indices
            scans += piece.scans
        skipped = reader.bad_scans if task.stop is None else None  # the whole log was read
    table = ExtractionTable.join(tables) if tables else _empty_table(extractor)
    write_parts(Path(task.dataset), task.log, task.start, indices, scans, table, staged=task.staged)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return ChunkResult(task.log, task.start, len(scans), len(table.first), skipped,
                       time.perf_counter() - started, peak_mb, os.getpid())  # fmt: skip


def _task_profile(task: ChunkTask) -> Any:
    """The sensor profile file given, else the log's own, measured from its first scans
    as ``scanlines run`` does (the same for every chunk of the log)."""
    from scanlines.runs.runner import log_profile
    from scanlines.sensor.profile import ProfileError, read_profile

    if task.sensor_profile is not None:
        return read_profile(task.sensor_profile)
    try:
        return log_profile(task.path, task.reader_options)
    except ProfileError:
        return None


def _empty_table(extractor: Any) -> Any:
    from scanlines.extraction import ExtractionTable

    return ExtractionTable.concatenate([], extractor.method, dict(extractor.params))


# -- checksums and the record of finished logs --------------------------------------------


def checksum(path: Path) -> str:
    """SHA-256 of a log's bytes (a bag folder: of its files, in name order)."""
    digest = hashlib.sha256()
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    for file in files:
        digest.update(file.name.encode())
        with open(file, "rb") as fh:
            while chunk := fh.read(1 << 20):
                digest.update(chunk)
    return digest.hexdigest()


def _fingerprint(task: ChunkTask, digest: str) -> dict[str, Any]:
    from scanlines.report import jsonable

    profile = task.sensor_profile
    return jsonable({"input_sha256": digest, "method": task.method, "preset": task.preset,
                     "params": task.params, "reader_options": task.reader_options.given(),
                     "sensor_profile_sha256": None if profile is None else checksum(Path(profile)),
                     })  # fmt: skip


# -- running ------------------------------------------------------------------------------


def run_fleet(
    inputs: Iterable[str | Path],
    dataset: str | Path,
    *,
    method: str = DEFAULT_METHOD,
    preset: str | None = None,
    params: dict[str, Any] | None = None,
    reader_options: ReaderOptions | Mapping[str, Any] | None = None,
    sensor_profile: str | Path | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    chunk_records: int = CHUNK_RECORDS,
    overwrite: bool = False,
    on_chunk: Callable[[ChunkResult], None] | None = None,
) -> FleetSummary:
    """Extract every log of ``inputs`` into the Parquet dataset ``dataset``.

    ``scheduler``: ``None`` runs ``jobs`` local processes; ``"local"`` starts a Dask
    ``LocalCluster`` of ``jobs`` workers; anything else is the address of a Dask
    scheduler. Returns one :class:`LogOutcome` per log; a failed log does not stop
    the others.
    """
    from scanlines.extractor import Extractor
    from scanlines.io.parquet import require_pyarrow

    require_pyarrow()
    Extractor(method, preset, **(params or {}))  # bad parameters fail before any work
    started = time.perf_counter()
    dataset = Path(dataset)
    if not dataset.parent.is_dir():
        raise ParameterError(f"{dataset}: the folder {dataset.parent} does not exist")
    created = not dataset.exists()
    dataset.mkdir(exist_ok=True)
    paths = expand_inputs(inputs)
    if not paths:
        raise ParameterError("no log to run")
    profile = None if sensor_profile is None else str(Path(sensor_profile).resolve())
    tasks, failed = plan(paths, dataset, method=method, preset=preset, params=params,
                         reader_options=reader_options, sensor_profile=profile,
                         chunk_records=chunk_records)  # fmt: skip
    tasks, done_before = _skip_finished(tasks, dataset, overwrite)
    outcomes = {o.log: o for o in failed + done_before}
    for task in tasks:
        outcomes.setdefault(task.log, LogOutcome(task.log, task.path))
    peaks: dict[int, float] = {}

    def record(result: ChunkResult) -> None:
        peaks[result.worker] = max(peaks.get(result.worker, 0.0), result.peak_mb)
        if on_chunk is not None:
            on_chunk(result)

    with _executor(jobs, scheduler) as (executor, engine):
        _collect(executor, tasks, outcomes, record)
    _finish_logs(dataset, tasks, outcomes)
    _tidy(dataset, created)
    order = {name: k for k, name in enumerate(log_names(paths))}
    summary = FleetSummary(sorted(outcomes.values(), key=lambda o: order.get(o.log, 0)))
    summary.seconds, summary.engine = time.perf_counter() - started, engine
    summary.worker_peak_mb = peaks
    return summary


def _tidy(dataset: Path, created: bool) -> None:
    """No empty folder left behind: those of failed logs, and the dataset itself when this
    run made it and every log failed."""
    from scanlines.io.parquet import remove_empty_folders

    remove_empty_folders(dataset)
    if created:
        with contextlib.suppress(OSError):  # only when empty
            dataset.rmdir()


def _skip_finished(
    tasks: list[ChunkTask], dataset: Path, overwrite: bool
) -> tuple[list[ChunkTask], list[LogOutcome]]:
    """Drop the tasks of logs finished with the same input, method and parameters. A log
    begun with them and interrupted (``_logs/NAME.pending.json``) starts again; rows of a
    log written from another input or with other options are an error unless
    ``overwrite``. Each log to run gets its pending record."""
    from scanlines.io.parquet import remove_log
    from scanlines.outputs import OutputError, write_text_atomically

    kept, skipped, decided = [], [], {}
    for task in tasks:
        if task.log not in decided:
            wanted = _fingerprint(task, checksum(Path(task.path)))
            done, pending = _records(dataset, task.log)
            if done.get("fingerprint") == wanted:
                decided[task.log] = "skip"
                outcome = LogOutcome(task.log, task.path, "skipped", "done before")
                outcome.scans, outcome.segments = done.get("scans", 0), done.get("segments", 0)
                skipped.append(outcome)
                continue
            written_otherwise = pending.get("fingerprint") != wanted
            if _has_rows(dataset, task.log) and written_otherwise and not overwrite:
                raise OutputError(
                    f"{dataset}: log {task.log} was written before from another input "
                    "or with other options; pass --overwrite to replace it"
                )
            remove_log(dataset, task.log)
            (dataset / "_logs").mkdir(exist_ok=True)
            write_text_atomically(
                dataset / "_logs" / f"{task.log}.pending.json",
                json.dumps({"log": task.log, "input": task.path, "fingerprint": wanted}),
            )
            decided[task.log] = "run"
        if decided[task.log] == "run":
            kept.append(task)
    return kept, skipped


def _records(dataset: Path, log: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """The finished and the pending record of ``log`` (empty when absent or unreadable)."""
    found = []
    for name in (f"{log}.json", f"{log}.pending.json"):
        try:
            found.append(json.loads((dataset / "_logs" / name).read_text()))
        except (OSError, ValueError):
            found.append({})
    return found[0], found[1]


def _has_rows(dataset: Path, log: str) -> bool:
    from scanlines.io.parquet import STAGING, TABLES

    return (dataset / "_logs" / f"{log}.json").exists() or any(
        (root / table / f"log={log}").exists()
        for root in (dataset, dataset / STAGING)
        for table in TABLES
    )


def _collect(executor, tasks, outcomes, on_chunk) -> None:
    futures = {executor.submit(extract_task, task): task for task in tasks}
    for future in cf.as_completed(futures):
        task = futures[future]
        outcome = outcomes[task.log]
        try:
            result = future.result()
        except (ScanlinesError, OSError) as error:
            outcome.status, outcome.reason = "failed", str(error)
            continue
        except Exception as error:  # a defect: report it with the log, go on
            outcome.status, outcome.reason = "failed", describe(error)
            continue
        outcome.chunks += 1
        outcome.scans += result.scans
        outcome.segments += result.segments
        outcome.seconds += result.seconds
        outcome.peak_mb = max(outcome.peak_mb, result.peak_mb)
        if result.skipped_scans is not None:
            outcome.skipped_scans = result.skipped_scans
        if on_chunk is not None:
            on_chunk(result)


def _finish_logs(dataset: Path, tasks: list[ChunkTask], outcomes: dict[str, LogOutcome]) -> None:
    """Remove the rows of failed logs; move the finished ones' parts into the tables and
    record them."""
    from scanlines.io.parquet import commit_log, remove_log
    from scanlines.outputs import write_text_atomically

    first_task = {}
    for task in tasks:
        first_task.setdefault(task.log, task)
    for name, task in first_task.items():
        outcome = outcomes[name]
        if outcome.status == "failed":
            remove_log(dataset, name)
            continue
        record = {"log": name, "input": task.path, "scans": outcome.scans,
                  "segments": outcome.segments, "skipped_scans": outcome.skipped_scans,
                  "fingerprint": _fingerprint(task, checksum(Path(task.path)))}  # fmt: skip
        commit_log(dataset, name)
        (dataset / "_logs").mkdir(exist_ok=True)
        write_text_atomically(dataset / "_logs" / f"{name}.json", json.dumps(record, indent=2))
        (dataset / "_logs" / f"{name}.pending.json").unlink(missing_ok=True)


def fleet_tasks(inputs: Iterable[str | Path], dataset: str | Path, **options: Any) -> list[Any]:
    """The work of a fleet run as ``dask.delayed`` objects, for a notebook with a Dask
    cluster of its own: ``dask.compute(*fleet_tasks(logs, "features"))``. One object per
    log: its chunk tasks, then the move of its parts into the tables (a
    :class:`ChunkResult` of the whole log). ``options`` are those of :func:`plan`.
    Finished-log records are not written (use :func:`run_fleet` with ``scheduler=`` for
    that)."""
    import dask

    from scanlines.io.parquet import discard_staged

    dataset = Path(dataset)
    dataset.mkdir(exist_ok=True)
    tasks, failed = plan(expand_inputs(inputs), dataset, **options)
    if failed:
        raise ParameterError("; ".join(f"{o.log}: {o.reason}" for o in failed))
    by_log: dict[str, list[Any]] = {}
    for task in tasks:
        if task.log not in by_log:
            discard_staged(dataset, task.log)  # left by an earlier, interrupted compute
        by_log.setdefault(task.log, []).append(dask.delayed(extract_task)(task))
    return [
        dask.delayed(commit_chunks)(str(dataset), log, chunks) for log, chunks in by_log.items()
    ]


def commit_chunks(dataset: str, log: str, chunks: list[ChunkResult]) -> ChunkResult:
    """Move the parts of ``log`` (written by ``chunks``) into the tables; the log's totals."""
    from scanlines.io.parquet import commit_log

    commit_log(Path(dataset), log)
    skipped = [c.skipped_scans for c in chunks if c.skipped_scans is not None]
    return ChunkResult(
        log,
        0,
        sum(c.scans for c in chunks),
        sum(c.segments for c in chunks),
        skipped[-1] if skipped else None,
        sum(c.seconds for c in chunks),
        max((c.peak_mb for c in chunks), default=0.0),
        chunks[0].worker if chunks else 0,
    )
