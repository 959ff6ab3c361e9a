"""Whole logs: describe one, and run an extractor over every scan of it.

Both stream: a few chunks of scans are in memory at a time, whatever the size of the log.
"""

from __future__ import annotations

import math
import os
import time
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.extraction import ExtractionTable
from scanlines.extractor import Extractor
from scanlines.reader_options import ReaderOptions, parse_scans, select_scans
from scanlines.scan import Scan
from scanlines.sensor.mounting import estimate_mounting
from scanlines.sensor.profile import (
    DEFAULT_SCANS,
    SensorProfile,
    estimate_profile,
)

__all__ = [
    "LogDescription",
    "RunSummary",
    "chunk_scans",
    "default_jobs",
    "describe_log",
    "extract_chunk",
    "log_profile",
    "measure_profile",
    "measured_scans",
    "parse_slice",
    "run_log",
    "run_log_to_file",
    "selected_count",
]


#: ``--scans`` as a slice (:func:`scanlines.reader_options.parse_scans`, one grammar).
parse_slice = parse_scans
#: The scans whose log index falls in a slice (:func:`scanlines.reader_options.select_scans`).
select = select_scans


def selected_count(scans_in_file: int | None, scans: slice) -> int | None:
    """How many scan records of a log of ``scans_in_file`` fall in ``scans`` (``None``
    when neither the log nor the selection bounds it; a declared 0 is taken as not known,
    as a damaged index says that of a log that holds scans)."""
    scans_in_file = scans_in_file or None
    if scans_in_file is None and scans.stop is None:
        return None
    stop = scans.stop if scans_in_file is None else min(scans.stop or scans_in_file, scans_in_file)
    return len(range(scans.start or 0, stop, scans.step or 1))


def log_profile(
    path: Any, reader_options: ReaderOptions, scans: slice = slice(None)
) -> SensorProfile:
    """The :class:`~scanlines.sensor.profile.SensorProfile` of a log, measured from its
    first selected scans (at most :data:`~scanlines.sensor.profile.DEFAULT_SCANS`).

    ``scanlines run`` without ``--sensor-profile`` extracts the whole log with this one
    profile, so every chunk, job and worker sees the same noise.
    """
    from scanlines.io import open_log

    with open_log(path, options=reader_options) as reader:
        return measure_profile(reader, scans, max_scans=DEFAULT_SCANS, source=str(path))


def run_profile(
    path: Any, reader_options: ReaderOptions, scans: slice, given: Any = None
) -> tuple[SensorProfile | None, str | None]:
    """The sensor profile a run of the log at ``path`` uses, and a note saying where it
    came from: the profile file ``given``; else measured from the log's first selected
    scans; else none (a log too short or too odd to measure: each scan's noise is then
    measured from itself)."""
    from scanlines.sensor.profile import ProfileError, read_profile

    if given is not None:
        return read_profile(given), None
    try:
        profile = log_profile(path, reader_options, scans)
    except ProfileError as error:
        return None, f"sensor profile: {error}; each scan's noise is measured from itself"
    name = getattr(path, "name", str(path))
    return profile, (
        f"sensor profile: measured from {measured_scans(scans, profile.scans)} of {name} "
        f"(noise {1000 * profile.noise_sigma0:.1f} mm + {100 * profile.noise_per_metre:.2f} % "
        "of range); `scanlines calibrate` saves one for --sensor-profile"
    )


def measured_scans(selection: slice, count: int) -> str:
    """Which scans ``count`` scans measured from the start of ``selection`` are, in words:
    ``"the first 500 scans"``, ``"scans 100-199"``, ``"50 scans (0, 10, ..., 490)"``."""
    start, step = selection.start or 0, selection.step or 1
    if start == 0 and step == 1:
        return f"the first {count} scans"
    last = start + (count - 1) * step
    if step == 1:
        return f"scans {start}-{last}"
    return f"{count} scans ({start}, {start + step}, ..., {last})"


def mounted_options(
    path: Any, reader_options: ReaderOptions, profile: SensorProfile | None
) -> tuple[ReaderOptions, str | None]:
    """Reader options that give the laser's pose where the log records only the robot's
    (the profile's mounting, for a reader that takes one), and a note when they do."""
    from scanlines.io import detect_format, open_log
    from scanlines.io import reader_option_names as options_of

    if profile is None or profile.mounting is None:
        return reader_options, None
    if "mounting" not in options_of(detect_format(path)):
        return reader_options, None
    options = reader_options.but(mounting=profile.mounting)
    with open_log(path, options=options) as reader:
        if not reader.moves_robot_poses:
            return options, None
        x, y, theta = profile.mounting
        return options, (
            f"world frame: {reader.message} records carry the robot's pose; moved by the "
            f"laser's mounting (x {x:.3f} m, y {y:.3f} m, theta {math.degrees(theta):.2f} "
            "deg) of the sensor profile"
        )


def measure_profile(
    reader: Any, scans: slice = slice(None), *, max_scans: int = DEFAULT_SCANS, source: str = ""
) -> SensorProfile:
    """The sensor profile of the first ``max_scans`` selected scans of ``reader``, with
    the laser's mounting on the robot where the log records it."""
    recorded: list[tuple[float, float, float]] = []

    def selected() -> Iterator[Scan]:
        for _, scan in select(reader.enumerate(), scans):
            mounting = reader.recorded_mounting
            if mounting is not None:
                recorded.append(mounting)
            yield scan

    profile = estimate_profile(selected(), max_scans=max_scans, source=source)
    return replace(profile, mounting=estimate_mounting(recorded[:max_scans]))


@dataclass
class LogDescription:
    """What ``scanlines info`` prints about a log."""

    format: str
    path: str
    scans: int = 0
    beams: dict[int, int] = field(default_factory=dict)
    field_of_view_deg: list[float] = field(default_factory=list)
    resolution_deg: list[float] = field(default_factory=list)
    range_min: float | None = None
    range_mean: float | None = None
    range_max: float | None = None
    no_return_share: float | None = None
    time_first: float | None = None
    time_last: float | None = None
    time_min: float | None = None
    time_max: float | None = None
    time_backwards_steps: int = 0
    with_pose: int = 0
    reader: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def describe_log(reader: Any) -> LogDescription:
    """Read the whole log once and summarise it (streaming)."""
    info = LogDescription(format=reader.format_name, path=str(reader.path))
    total_beams = valid_beams = 0
    range_mean = 0.0  # a running mean: a sum of ranges near 1e308 would overflow
    low, high = math.inf, -math.inf
    previous_time = None
    for scan in reader:
        info.scans += 1
        n = len(scan)
        info.beams[n] = info.beams.get(n, 0) + 1
        step = abs(math.degrees(scan.angle_increment))
        _add_unique(info.resolution_deg, round(step, 6))
        _add_unique(info.field_of_view_deg, round(step * n, 4))
        valid = scan.ranges[scan.valid]
        total_beams += n
        valid_beams += valid.size
        if valid.size:
            scan_mean = float(np.sum(valid / valid.size))  # no term can overflow
            range_mean += (scan_mean - range_mean) * (valid.size / valid_beams)
            low, high = min(low, float(valid.min())), max(high, float(valid.max()))
        info.with_pose += scan.pose is not None
        stamp = scan.timestamp
        if stamp is not None and math.isfinite(stamp):
            info.time_first = stamp if info.time_first is None else info.time_first
            info.time_last = stamp
            info.time_min = stamp if info.time_min is None else min(info.time_min, stamp)
            info.time_max = stamp if info.time_max is None else max(info.time_max, stamp)
            if previous_time is not None and stamp < previous_time:
                info.time_backwards_steps += 1
            previous_time = stamp
    if valid_beams:
        info.range_min, info.range_max = low, high
        info.range_mean = range_mean
    if total_beams:
        info.no_return_share = 1.0 - valid_beams / total_beams
    info.reader = reader.info()
    return info


def _add_unique(values: list[float], value: float, limit: int = 8) -> None:
    if value not in values and len(values) < limit:
        values.append(value)


@dataclass
class RunSummary:
    """Counts and timings of :func:`run_log`.

    ``scans`` were written; ``skipped_scans`` scan records were dropped as malformed
    (``--on-error skip``), by reason in ``skip_reasons``; ``skipped_other`` other records
    were dropped: malformed ones (odometry, parameters) and those ignored by design
    (other topics, other message names, by name in ``ignored_records``).

    ``extract_seconds`` is the time in the extraction kernels, summed over jobs;
    ``total_seconds`` the wall time, end to end.
    """

    scans: int = 0
    segments: int = 0
    breakpoints: int = 0
    corners: int = 0
    skipped_scans: int = 0
    skip_reasons: dict[str, int] = field(default_factory=dict)
    skipped_other: int = 0
    ignored_records: dict[str, int] = field(default_factory=dict)
    extract_seconds: float = 0.0
    total_seconds: float = 0.0
    jobs: int = 1
    method: str = ""
    params: dict[str, Any] = field(default_factory=dict)

    def per_scan(self, count: int) -> float:
        return count / self.scans if self.scans else 0.0

    @property
    def microseconds_per_scan(self) -> float:
        return 1e6 * self.extract_seconds / self.scans if self.scans else 0.0

    @property
    def scans_per_second(self) -> float:
        return self.scans / self.total_seconds if self.total_seconds > 0 else 0.0


CHUNK_SCANS = 256
"""Scans extracted together by :meth:`Extractor.batch` in :func:`run_log` (memory is O(chunk))."""


@dataclass
class _Chunk:
    """Consecutive selected scans of one sensor geometry, and what became of them."""

    indices: list[int]
    scans: list[Scan]
    table: ExtractionTable | None = None
    encoded: Any = None
    seconds: float = 0.0


def default_jobs() -> int:
    """Every core this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def run_log(
    reader: Any,
    extractor: Extractor,
    *,
    writer: Any | None = None,
    scans: slice = slice(None),
    on_scan: Callable[[int], None] | None = None,
    chunk: int = CHUNK_SCANS,
    jobs: int = 1,
) -> RunSummary:
    """Extract features from every selected scan of ``reader``; write them if ``writer`` is given.

    Consecutive scans of one sensor geometry are stacked in chunks of ``chunk`` and go
    through :meth:`Extractor.batch` (the same results as one call per scan), then the
    writer encodes the chunk at once. With ``jobs > 1`` that work runs on a pool of
    threads (the kernels release the GIL) while this thread reads the log and writes;
    chunks are written in log order, so the output is the same bytes for any ``jobs``.
    ``on_scan`` is called with each log index after it is written (progress bars).
    """
    if jobs < 1:
        raise ParameterError(f"jobs must be at least 1, got {jobs}")
    summary = RunSummary(method=extractor.method, params=dict(extractor.params), jobs=jobs)
    started = time.perf_counter()
    chunks = chunk_scans(select(reader.enumerate(), scans), chunk)

    def process(piece: _Chunk) -> _Chunk:
        return _process(piece, extractor, writer)

    if jobs == 1:
        done = map(process, chunks)
        for piece in done:
            _write(piece, writer, summary, on_scan)
    else:
        with ThreadPoolExecutor(jobs, thread_name_prefix="scanlines-run") as pool:
            for piece in _ordered(pool, process, chunks, ahead=2 * jobs):
                _write(piece, writer, summary, on_scan)
    _count_skipped(reader, summary)
    summary.total_seconds = time.perf_counter() - started
    return summary


#: ``reader.skipped`` keys that are not records (nothing was lost).
NOT_RECORDS = frozenset({"blank", "comment", "header"})


def _count_skipped(reader: Any, summary: RunSummary) -> None:
    summary.skipped_scans = int(getattr(reader, "bad_scans", 0))
    summary.skip_reasons = dict(getattr(reader, "skip_reasons", {}))
    ignored = {k: v for k, v in getattr(reader, "skipped", {}).items() if k not in NOT_RECORDS}
    summary.ignored_records = ignored
    summary.skipped_other = int(getattr(reader, "bad_other", 0)) + sum(ignored.values())


def chunk_scans(indexed: Iterator[tuple[int, Scan]], size: int) -> Iterator[_Chunk]:
    """``(index, scan)`` pairs in chunks of at most ``size`` consecutive scans of one sensor
    geometry (what :func:`run_log` extracts at once)."""
    piece = _Chunk([], [])
    for index, scan in indexed:
        if piece.scans and (
            len(piece.scans) >= size or _geometry(scan) != _geometry(piece.scans[0])
        ):
            yield piece
            piece = _Chunk([], [])
        piece.indices.append(index)
        piece.scans.append(scan)
    if piece.scans:
        yield piece


def _ordered(pool: ThreadPoolExecutor, work: Callable, items: Iterator, ahead: int) -> Iterator:
    """``work`` of each item on ``pool``, results in the items' order, at most ``ahead``
    items in flight (memory stays bounded whatever the log's length)."""
    pending: deque[Future] = deque()
    for item in items:
        pending.append(pool.submit(work, item))
        if len(pending) >= ahead:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


def _geometry(scan: Scan) -> tuple[int, float, float, float, float]:
    return (len(scan), scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)


def extract_chunk(piece: _Chunk, extractor: Extractor) -> _Chunk:
    """Extract a chunk of same-geometry scans (from :func:`chunk_scans`) at once: sets its
    ``table`` and the ``seconds`` it took."""
    first = piece.scans[0]
    before = time.perf_counter()
    piece.table = extractor.batch(
        np.stack([scan.ranges for scan in piece.scans]),
        first.angle_min,
        first.angle_increment,
        first.range_min,
        first.range_max,
    )
    piece.seconds = time.perf_counter() - before
    return piece


def _process(piece: _Chunk, extractor: Extractor, writer: Any | None) -> _Chunk:
    """Extract a chunk of same-geometry scans at once, and encode it for the writer."""
    extract_chunk(piece, extractor)
    if hasattr(writer, "encode_chunk"):
        piece.encoded = writer.encode_chunk(piece.indices, piece.scans, piece.table)
    return piece


def _write(
    piece: _Chunk,
    writer: Any | None,
    summary: RunSummary,
    on_scan: Callable[[int], None] | None,
) -> None:
    """Write and count a processed chunk."""
    table = piece.table
    summary.extract_seconds += piece.seconds
    summary.scans += len(table)
    summary.segments += len(table.first)
    summary.breakpoints += len(table.breakpoints)
    summary.corners += len(table.corners)
    if hasattr(writer, "write_chunk"):
        writer.write_chunk(piece.indices, piece.scans, table, piece.encoded)
    elif writer is not None:  # any object with write(index, scan, extraction)
        for index, scan, extraction in zip(piece.indices, piece.scans, table, strict=True):
            writer.write(index, scan, extraction)
    if on_scan is not None:
        for index in piece.indices:
            on_scan(index)


def run_log_to_file(
    reader: Any,
    extractor: Extractor,
    out: Any,
    *,
    frame: str = "sensor",
    scans: slice = slice(None),
    on_scan: Callable[[int], None] | None = None,
    input_name: str | None = None,
    jobs: int = 1,
    overwrite: bool = False,
) -> RunSummary:
    """:func:`run_log`, writing to ``out`` (format by extension: :func:`scanlines.io.open_writer`).

    The output appears complete, with its ``.meta.json``, or not at all; an existing one
    is replaced only with ``overwrite``.
    """
    from scanlines.io import open_writer

    meta = {
        "input": input_name or str(reader.path),
        "method": extractor.method,
        "params": dict(extractor.params),
        "reader": reader.options(),
        "sensor_profile": (
            None if extractor.sensor_profile is None else extractor.sensor_profile.to_dict()
        ),
        "scans": ":".join(
            "" if v is None else str(v) for v in (scans.start, scans.stop, scans.step)
        ),
    }
    with open_writer(out, meta=meta, frame=frame, overwrite=overwrite) as writer:
        summary = run_log(reader, extractor, writer=writer, scans=scans, on_scan=on_scan, jobs=jobs)
        writer.update_meta(
            counts={
                "scans": summary.scans,
                "skipped_scan_records": summary.skipped_scans,
                "skip_reasons": summary.skip_reasons,
                "skipped_other_records": summary.skipped_other,
            }
        )
    return summary
