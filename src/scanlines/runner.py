"""Whole logs: describe one, and run an extractor over every scan of it.

Both stream: one scan is in memory at a time, whatever the size of the log.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.extractor import Extractor
from scanlines.scan import Scan
from scanlines.sensor_profile import DEFAULT_SCANS, SensorProfile, estimate_profile

__all__ = [
    "LogDescription",
    "RunSummary",
    "describe_log",
    "log_profile",
    "parse_slice",
    "run_log",
    "run_log_to_file",
]


def parse_slice(text: str | None) -> slice:
    """``"100:200"``, ``":50"``, ``"10:"``, ``"::5"`` or ``"7"`` as a slice of scan indices."""
    if text is None or text.strip() in ("", ":"):
        return slice(None)
    parts = text.split(":")
    if len(parts) > 3:
        raise ParameterError(f"--scans takes start:stop[:step], got {text!r}")
    try:
        values = [int(p) if p.strip() else None for p in parts]
    except ValueError:
        raise ParameterError(f"--scans takes integers start:stop[:step], got {text!r}") from None
    if len(values) == 1:
        start = values[0]
        return slice(start, None if start == -1 else start + 1)
    if len(values) == 3 and values[2] is not None and values[2] <= 0:
        raise ParameterError(f"--scans step must be positive, got {text!r}")
    if any(v is not None and v < 0 for v in values):
        raise ParameterError(f"--scans takes non-negative indices (the log streams), got {text!r}")
    return slice(*values)


def select(indexed: Iterator[tuple[int, Scan]], scans: slice) -> Iterator[tuple[int, Scan]]:
    """The scans whose log index falls in ``scans``, stopping early past its end."""
    start = scans.start or 0
    step = scans.step or 1
    for index, scan in indexed:
        if scans.stop is not None and index >= scans.stop:
            break
        if index >= start and (index - start) % step == 0:
            yield index, scan


def log_profile(
    path: Any, reader_options: dict[str, Any], scans: slice = slice(None)
) -> SensorProfile:
    """The :class:`~scanlines.sensor_profile.SensorProfile` of a log, measured from its
    first selected scans (at most :data:`~scanlines.sensor_profile.DEFAULT_SCANS`).

    ``scanlines run`` without ``--sensor-profile`` extracts the whole log with this one
    profile, so every chunk, job and worker sees the same noise.
    """
    from scanlines.io import open_log

    with open_log(path, **reader_options) as reader:
        selected = (scan for _, scan in select(reader.enumerate(), scans))
        return estimate_profile(selected, max_scans=DEFAULT_SCANS, source=str(path))


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
    range_sum = 0.0
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
            range_sum += float(valid.sum())
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
        info.range_mean = range_sum / valid_beams
    if total_beams:
        info.no_return_share = 1.0 - valid_beams / total_beams
    info.reader = reader.info()
    return info


def _add_unique(values: list[float], value: float, limit: int = 8) -> None:
    if value not in values and len(values) < limit:
        values.append(value)


@dataclass
class RunSummary:
    """Counts and timings of :func:`run_log`."""

    scans: int = 0
    segments: int = 0
    breakpoints: int = 0
    corners: int = 0
    skipped_records: int = 0
    extract_seconds: float = 0.0
    total_seconds: float = 0.0
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


def run_log(
    reader: Any,
    extractor: Extractor,
    *,
    writer: Any | None = None,
    scans: slice = slice(None),
    on_scan: Callable[[int], None] | None = None,
    chunk: int = CHUNK_SCANS,
) -> RunSummary:
    """Extract features from every selected scan of ``reader``; write them if ``writer`` is given.

    Consecutive scans of one sensor geometry are stacked in chunks of ``chunk`` and
    go through :meth:`Extractor.batch` (the same results as one call per scan).
    ``on_scan`` is called with each log index after it is processed (progress bars).
    """
    summary = RunSummary(method=extractor.method, params=dict(extractor.params))
    started = time.perf_counter()
    pending: list[tuple[int, Scan]] = []
    for index, scan in select(reader.enumerate(), scans):
        if pending and (len(pending) >= chunk or _geometry(scan) != _geometry(pending[0][1])):
            _flush(pending, extractor, writer, summary, on_scan)
        pending.append((index, scan))
    if pending:
        _flush(pending, extractor, writer, summary, on_scan)
    summary.skipped_records = int(getattr(reader, "error_count", 0))
    summary.total_seconds = time.perf_counter() - started
    return summary


def _geometry(scan: Scan) -> tuple[int, float, float, float, float]:
    return (len(scan), scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)


def _flush(
    pending: list[tuple[int, Scan]],
    extractor: Extractor,
    writer: Any | None,
    summary: RunSummary,
    on_scan: Callable[[int], None] | None,
) -> None:
    """Extract a chunk of same-geometry scans at once, then write and count them in order."""
    first = pending[0][1]
    before = time.perf_counter()
    results = extractor.batch(
        np.stack([scan.ranges for _, scan in pending]),
        first.angle_min,
        first.angle_increment,
        first.range_min,
        first.range_max,
    )
    summary.extract_seconds += time.perf_counter() - before
    for (index, scan), result in zip(pending, results, strict=True):
        summary.scans += 1
        summary.segments += len(result)
        summary.breakpoints += int(result.breakpoints.size)
        summary.corners += int(result.corners.size)
        if writer is not None:
            writer.write(index, scan, result)
        if on_scan is not None:
            on_scan(index)
    pending.clear()


def run_log_to_file(
    reader: Any,
    extractor: Extractor,
    out: Any,
    *,
    frame: str = "sensor",
    scans: slice = slice(None),
    on_scan: Callable[[int], None] | None = None,
    input_name: str | None = None,
) -> RunSummary:
    """:func:`run_log`, writing to ``out`` (format by extension: :func:`scanlines.io.open_writer`).

    The output appears complete, with its ``.meta.json``, or not at all.
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
    with open_writer(out, meta=meta, frame=frame) as writer:
        summary = run_log(reader, extractor, writer=writer, scans=scans, on_scan=on_scan)
        writer.update_meta(
            counts={"scans": summary.scans, "skipped_records": summary.skipped_records}
        )
    return summary
