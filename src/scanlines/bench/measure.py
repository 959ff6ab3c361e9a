"""Speed of the registered methods, measured in one process: ``scanlines bench``.

What is timed
-------------
Every selected method on the same scans, in one process:

* the shipped real excerpts (:func:`scanlines.data.sample`: ``"intel"``, ``"freiburg"``),
  the first ``real_scans`` scans of each;
* simulated scans of each sensor preset (:data:`scanlines.sim.SENSORS`): scan ``i`` is
  ``random_scene(seed + i, sensor).scan(seed + i).scan``;
* a scaling run: one scene scanned over the same 180 deg field of view at increasing
  angular resolution (``beam_counts``, 100 to 10,000 beams by default), to show whether
  the cost is linear in the number of beams;
* :meth:`Extractor.batch <scanlines.Extractor.batch>` against the single-call loop on the
  real excerpts (scans of one sensor, equal beam count, stacked);
* the pipeline of ``scanlines run`` on the intel excerpt, cold start in a fresh process,
  scaling with jobs and the floor (:mod:`scanlines.bench.pipeline`);
* optionally a :mod:`cProfile` run of the default extractor (``adaptive``) over the intel
  excerpt: the functions within scanlines by cumulative time.

How
---
One :class:`~scanlines.Extractor` per method (default parameters) for the whole run.
Every time is taken by :mod:`scanlines.bench.timing`: per (method, dataset)
``repeats`` passes over the dataset's scans in a fixed order, interleaved between methods,
every timed call directly after an untimed call on the same scan; every timed call is one
sample. Reported: median and 90th percentile of the samples in microseconds per scan, and
scans per second (``1e6 / mean``). The ratio of a method is its median over the reference
method's median on the same dataset in the same run
(:data:`~scanlines.bench.timing.REFERENCE`, or the first selected method when it is
not selected). A method that raises on a scan is reported as an error for that dataset
(the scan and the message) and not timed further there; the bench goes on. The batch
comparison times whole passes over the stack (:data:`BATCH_VARIANTS`) by the same rule.

The results are :mod:`scanlines.bench.results`, the page
:mod:`tools.bench.performance_page`. ``import scanlines.bench.measure`` needs
only numpy; the command (``scanlines.cli.bench``) adds the rich tables and the progress
bar.
"""

from __future__ import annotations

import cProfile
import dataclasses
import datetime as _dt
import itertools
import math
import pstats
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines import Extractor, ParameterError, Scan, method_names
from scanlines.bench.config import (
    DEFAULT_BEAMS,
    QUICK_BEAMS,
    SAMPLE_NAMES,
    BenchConfig,
)
from scanlines.bench.machine import load_average, machine_info
from scanlines.bench.results import (
    BatchResult,
    BatchRow,
    BenchResult,
    DatasetResult,
    ScalingResult,
    Timing,
)
from scanlines.bench.timing import REFERENCE, Timed, time_calls
from scanlines.builtin_methods import DEFAULT_METHOD

__all__ = [
    "BATCH_VARIANTS",
    "DEFAULT_BEAMS",
    "QUICK_BEAMS",
    "BenchConfig",
    "profile_extractor",
    "run",
]

Progress = Callable[[str, int, int], None]
"""``progress(stage, done, total)``: called after every unit of work."""


# --------------------------------------------------------------------------- configuration


@dataclass
class _Dataset:
    name: str
    kind: str
    description: str
    scans: list[Scan] = field(default_factory=list)

    @property
    def beam_counts(self) -> list[int]:
        return sorted({len(s) for s in self.scans})


def _real_dataset(name: str, n: int | None) -> _Dataset:
    from scanlines.data import sample
    from scanlines.io import open_log

    scans = list(itertools.islice(open_log(sample(name)), n))
    if not scans:
        raise ParameterError(f"the {name} excerpt holds no scans")
    descriptions = {
        "intel": "Intel Research Lab, SICK LMS (real)",
        "freiburg": "Freiburg building 079, SICK LMS (real)",
    }
    return _Dataset(name, "real", descriptions.get(name, f"{name} (real)"), scans)


def _sim_dataset(sensor: str, n: int, seed: int) -> _Dataset:
    from scanlines.sim import get_sensor, random_scene

    spec = get_sensor(sensor)
    scans = [random_scene(seed + i, spec).scan(seed + i).scan for i in range(n)]
    return _Dataset(
        f"sim:{sensor}", "simulated", f"{spec.description} (simulated, one scene per scan)", scans
    )


def _scaling_sensor(n_beams: int):
    from scanlines.sim import get_sensor

    return dataclasses.replace(
        get_sensor("lms_1deg"),
        n_beams=n_beams,
        angle_increment=math.pi / (n_beams - 1),
        angle_min=-math.pi / 2,
    )


# --------------------------------------------------------------------------- measuring


def _measure(
    extractors: dict[str, Extractor],
    scans: Sequence[Scan],
    repeats: int,
    reference: str,
    tick: Callable[[], None],
) -> dict[str, Timing]:
    """Per-scan timings of every extractor over ``scans``, with ratios to ``reference``."""
    timed = time_calls(extractors, scans, repeats, catch=True, after_pass=lambda _: tick())
    timings = {m: Timing.from_timed(t) for m, t in timed.items()}
    _set_ratios(timings, reference)
    return timings


def _set_ratios(timings: dict[str, Timing], reference: str) -> None:
    ref = timings.get(reference)
    for m, t in timings.items():
        if not t.ok or ref is None or not ref.ok or not ref.median_us:
            t.ratio = None
        elif m == reference:
            t.ratio = 1.0
        else:
            t.ratio = t.median_us / ref.median_us


def _stack_group(scans: Sequence[Scan]) -> list[Scan]:
    """The largest group of scans sharing beam count, angles and range limits."""
    groups: dict[tuple, list[Scan]] = {}
    for s in scans:
        key = (len(s), s.angle_min, s.angle_increment, s.range_min, s.range_max)
        groups.setdefault(key, []).append(s)
    return max(groups.values(), key=len)


BATCH_VARIANTS = ("loop", "loop_rows", "batch")
"""How a stack of scans is extracted: the loop over the log's scans, the loop building
``Scan(row, ...)`` from the stacked ranges (as ``batch()`` does), one ``batch()`` call."""


def _measure_batch(
    extractors: dict[str, Extractor],
    scans: Sequence[Scan],
    repeats: int,
    tick: Callable[[], None],
) -> tuple[int, int, dict[str, BatchRow]]:
    """Each :data:`BATCH_VARIANTS` of every extractor over the largest stackable group.

    Returns the group's scan and beam counts and a row per method, times in us per scan.
    """
    group = _stack_group(scans)
    first = group[0]
    stack = np.stack([s.ranges for s in group])
    geometry = (first.angle_min, first.angle_increment, first.range_min, first.range_max)

    def variants(ex: Extractor) -> dict[str, Callable[[np.ndarray], None]]:
        def loop(_stack: np.ndarray) -> None:
            for s in group:
                ex(s)

        def loop_rows(rows: np.ndarray) -> None:
            for row in rows:
                ex(Scan(row, *geometry))

        def batch(rows: np.ndarray) -> None:
            ex.batch(rows, *geometry)

        return {"loop": loop, "loop_rows": loop_rows, "batch": batch}

    calls = {(m, k): call for m, ex in extractors.items() for k, call in variants(ex).items()}
    timed = time_calls(calls, [stack], repeats, catch=True, after_pass=lambda _: tick())
    rows = {m: _batch_row({k: timed[m, k] for k in BATCH_VARIANTS}, len(group)) for m in extractors}
    return len(group), len(first), rows


def _batch_row(timed: dict[str, Timed[Any]], n_scans: int) -> BatchRow:
    for variant, t in timed.items():
        if t.failure is not None:
            error = t.failure.error
            return BatchRow(error=f"{variant}: {type(error).__name__}: {error}"[:300])
    per = {k: float(np.median(t.samples_ns[:, 0])) / 1000.0 / n_scans for k, t in timed.items()}
    return BatchRow(
        loop_us=per["loop"],
        loop_rows_us=per["loop_rows"],
        batch_us=per["batch"],
        ratio=per["batch"] / per["loop"] if per["loop"] > 0 else None,
    )


# --------------------------------------------------------------------------- profile


def profile_extractor(scans: Sequence[Scan], top: int = 15, method: str = DEFAULT_METHOD) -> dict:
    """:mod:`cProfile` of ``Extractor(method)`` over ``scans``.

    Returns the profiled time and two lists: the ``top`` functions within scanlines by
    cumulative time, and the ``top`` functions of any code by own time.
    """
    import scanlines

    extractor = Extractor(method)
    extractor(scans[0])  # warm the bearing tables, as a long-running user would have them
    profiler = cProfile.Profile()
    profiler.enable()
    for scan in scans:
        extractor(scan)
    profiler.disable()
    stats = pstats.Stats(profiler)
    # Percentages are of the profiled total; the outermost cumulative time can exceed the
    # sum of own times by the profiler's bookkeeping, so take the larger of the two.
    total = max(
        float(stats.total_tt),  # type: ignore[attr-defined]
        max((v[3] for v in stats.stats.values()), default=0.0),  # type: ignore[attr-defined]
        1e-12,
    )
    package = Path(scanlines.__file__).resolve().parent
    root = package.parent

    def where(filename: str, line: int) -> tuple[str, bool]:
        path = Path(filename)
        try:
            inside = path.resolve().is_relative_to(package)
        except (OSError, ValueError):
            inside = False
        if inside:
            return f"{path.resolve().relative_to(root)}:{line}", True
        if filename == "~":
            return "(built-in)", False
        parts = path.parts
        if "site-packages" in parts:
            parts = parts[parts.index("site-packages") + 1 :]
        return f"{'/'.join(parts[-3:])}:{line}", False

    rows = []
    for (filename, line, func), (_cc, ncalls, own, cumulative, _callers) in stats.stats.items():  # type: ignore[attr-defined]
        place, inside = where(filename, line)
        rows.append(
            {
                "function": func,
                "where": place,
                "inside": inside,
                "calls": int(ncalls),
                "own_s": float(own),
                "cumulative_s": float(cumulative),
                "own_pct": 100.0 * own / total,
                "cumulative_pct": 100.0 * cumulative / total,
            }
        )
    cumulative = sorted((r for r in rows if r["inside"]), key=lambda r: -r["cumulative_s"])
    own = sorted(rows, key=lambda r: -r["own_s"])
    for r in rows:
        del r["inside"]
    return {
        "method": method,
        "dataset": "intel",
        "n_scans": len(scans),
        "profiled_s": total,
        "us_per_scan_profiled": 1e6 * total / len(scans),
        "cumulative": cumulative[:top],
        "own": own[:top],
    }


# --------------------------------------------------------------------------- run


def run(
    config: BenchConfig | None = None,
    *,
    command: str = "",
    progress: Progress | None = None,
) -> BenchResult:
    """Time the methods as ``config`` says; see the module docstring.

    Raises
    ------
    ParameterError
        For a bad configuration (checked before anything is timed).
    """
    config = (config or BenchConfig()).validated()
    started = _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat()
    machine = machine_info()
    t0 = time.perf_counter()
    reference, note = _reference(config.methods)
    extractors = {m: Extractor(m) for m in config.methods}
    tick = _Ticks(config, progress)

    sets: list[_Dataset] = []
    for name in SAMPLE_NAMES:
        sets.append(_real_dataset(name, config.real_scans))
        tick(f"reading {name}")()
    for sensor in config.sensors:
        sets.append(_sim_dataset(sensor, config.sim_scans, config.seed))
        tick(f"simulating {sensor}")()
    results = [
        DatasetResult(
            d.name,
            d.kind,
            d.description,
            len(d.scans),
            d.beam_counts,
            _measure(extractors, d.scans, config.repeats, reference, tick(d.name)),
        )
        for d in sets
    ]
    scaling = _scaling(extractors, config, reference, tick) if config.beam_counts else None
    batch = []
    if config.batch:
        for d in sets[: len(SAMPLE_NAMES)]:
            n, beams, rows = _measure_batch(
                extractors, d.scans, config.repeats, tick(f"batch: {d.name}")
            )
            batch.append(BatchResult(d.name, n, beams, rows))
    profile = None
    if config.profile:
        scans = _real_dataset("intel", config.profile_scans).scans
        profile = profile_extractor(scans, config.profile_top)
        tick("profiling adaptive")()
    pipeline = None
    if config.pipeline:
        from scanlines.bench.pipeline import measure_pipeline
        from scanlines.data import sample

        pipeline = measure_pipeline(
            sample("intel"),
            repeats=config.repeats,
            max_jobs=config.jobs,
            max_scans=config.pipeline_scans,
            with_cold_start=config.cold_start,
            tick=lambda stage: tick(stage)(),
        )
    return BenchResult(
        config=config,
        command=command,
        machine=machine,
        reference=reference,
        reference_note=note,
        datasets=results,
        scaling=scaling,
        batch=batch,
        profile=profile,
        started=started,
        elapsed_s=round(time.perf_counter() - t0, 1),
        load_after=load_average(),
        pipeline=pipeline,
    )


def _reference(methods: tuple[str, ...]) -> tuple[str, str]:
    """The method ratios refer to, and a sentence saying so."""
    if REFERENCE in methods:
        return REFERENCE, f"Ratios are to {REFERENCE}, measured in the same run."
    why = "not registered" if REFERENCE not in method_names() else "not selected"
    note = (
        f"{REFERENCE} is {why}: ratios are to {methods[0]}, the first selected method, "
        "measured in the same run."
    )
    return methods[0], note


class _Ticks:
    """Counts units of work for ``progress``: ``tick(stage)()`` after each one."""

    def __init__(self, config: BenchConfig, progress: Progress | None) -> None:
        passes = config.repeats * len(config.methods)
        n_sets = len(SAMPLE_NAMES) + len(config.sensors)
        self.total = (
            n_sets  # reading or simulating
            + n_sets * passes
            + len(config.beam_counts) * (1 + passes)
            + (len(SAMPLE_NAMES) * passes * len(BATCH_VARIANTS) if config.batch else 0)
            + (1 if config.profile else 0)
            + ((3 + config.cold_start) if config.pipeline else 0)
        )
        self.done = 0
        self.progress = progress

    def __call__(self, stage: str) -> Callable[[], None]:
        def advance() -> None:
            self.done += 1
            if self.progress is not None:
                self.progress(stage, self.done, self.total)

        return advance


def _scaling(
    extractors: dict[str, Extractor], config: BenchConfig, reference: str, tick: _Ticks
) -> ScalingResult:
    """One scene scanned at every beam count of ``config``, timed like a dataset."""
    from scanlines.sim import random_scene

    scene = random_scene(config.seed, _scaling_sensor(181))
    entries = []
    for n in config.beam_counts:
        spec = _scaling_sensor(n)
        scans = [scene.scan(config.seed + i, sensor=spec).scan for i in range(config.scaling_scans)]
        tick(f"scaling: simulating {n} beams")()
        advance = tick(f"scaling: {n} beams")
        entries.append((n, _measure(extractors, scans, config.repeats, reference, advance)))
    description = (
        f"one {scene.kind} scene (seed {config.seed}) scanned by the lms_1deg preset "
        f"widened to -90..+90 deg at pi/(beams-1) steps; {config.scaling_scans} noise "
        f"draws per count x {config.repeats} repeat{'s' if config.repeats != 1 else ''}"
    )
    return ScalingResult(description, config.scaling_scans, entries, config.methods)
