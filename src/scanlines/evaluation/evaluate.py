"""Score method specs on simulated scans with exact ground truth: :func:`evaluate`.

Run one or more method specs (:mod:`scanlines.evaluation.specs`) on the same generated
scenes of every sensor preset (:mod:`scanlines.evaluation.scenes`), score each
extraction with :func:`scanlines.evaluation.metrics.score` and pool the scores per
sensor and spec::

    from scanlines.evaluation.evaluate import evaluate

    result = evaluate(["adaptive", "adaptive:paper"], sensors=["tim571"], n=20)
    result.to_csv("out/")              # per_scan.csv, summary.csv
    result.to_json("out/summary.json")

The spec ``truth`` adds the truth row (:mod:`scanlines.evaluation.truth_row`), scored
like every method. :func:`worst_scans` ranks the scans by event F1; the figures are in
:mod:`scanlines.viz.evaluation`.

Timing
------
``us`` is the time of the extraction call alone, taken by
:mod:`scanlines.bench.timing` (one pass per scene: every spec on the scene's scan,
an untimed call, then the timed one), in microseconds; summaries report its median (and
mean) per sensor and spec. With ``workers > 1`` the processes share the machine, so
times are less comparable; compare speeds with ``scanlines bench``. For the truth row it
is the time of building the row from the truth.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from functools import lru_cache, partial
from typing import Any

import numpy as np

from scanlines import Extraction, ParameterError
from scanlines.bench.timing import time_calls
from scanlines.evaluation.eval_results import (
    TABLE_COLUMNS,
    WORST_BY,
    EvalConfig,
    EvalResult,
    ScanRecord,
    SummaryRecord,
    WorstScan,
    event_f1,
    tolerance_caption,
    tolerances_dict,
    worst_scans,
)
from scanlines.evaluation.metrics import aggregate, score
from scanlines.evaluation.scenes import (
    DEFAULT_SCENES,
    OnScene,
    SceneCase,
    SceneSet,
    check_sensors,
    make_scene,
    scene_recipe,
)
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.evaluation.truth_row import truth_extraction
from scanlines.sim import get_sensor

__all__ = [
    "ALL_SENSORS",
    "TABLE_COLUMNS",
    "WORST_BY",
    "EvalConfig",
    "EvalResult",
    "ScanRecord",
    "SummaryRecord",
    "WorstScan",
    "evaluate",
    "event_f1",
    "extract_case",
    "tolerance_caption",
    "tolerances_dict",
    "worst_scans",
]

ALL_SENSORS = "all"
"""The ``sensor`` of summary rows pooled over every sensor."""


# --------------------------------------------------------------------------- running


def evaluate(
    specs: Iterable[str | MethodSpec],
    sensors: Sequence[str] | None = None,
    n: int | None = None,
    seed: int = 0,
    *,
    tol: Tolerances | None = None,
    noise: str = "realistic",
    scenes: SceneSet | None = None,
    workers: int = 1,
    on_scene: OnScene | None = None,
    clutter: bool = False,
) -> EvalResult:
    """Run every spec on the same scans and score them against the truth.

    Parameters
    ----------
    specs:
        Method specs (strings as in :func:`~scanlines.evaluation.specs.parse_spec`, or
        :class:`~scanlines.evaluation.specs.MethodSpec`).
    sensors:
        Sensor names (presets, or family names such as ``"family-03"``, see
        :mod:`scanlines.sim.family`); all of :data:`~scanlines.sim.SENSORS` when
        ``None``. With ``scenes``, a selection of the set's sensors.
    n:
        Scenes per sensor; 100 when ``None``. With ``scenes``, at most this many of
        each sensor (all when ``None``).
    seed:
        Base seed (see :func:`~scanlines.evaluation.scenes.scene_seed`); ignored with
        ``scenes``.
    tol:
        Tolerances; :class:`~scanlines.evaluation.scores.Tolerances` defaults when ``None``.
    noise:
        ``"realistic"`` or ``"exact"``; ignored with ``scenes``.
    scenes:
        Evaluate on this set instead of generating scenes.
    workers:
        Processes; each scene is generated once and all specs run on it.
    on_scene:
        Called as ``on_scene(done, total)`` after each scene.
    clutter:
        Generate clutter scenes (:data:`scanlines.sim.CLUTTER_KINDS`); ignored with
        ``scenes``.

    Returns
    -------
    EvalResult

    Raises
    ------
    ParameterError
        For a bad spec, an unknown sensor, ``n < 1``, a negative seed, an unknown
        noise or ``workers < 1``.
    """
    parsed = parse_specs(specs)
    tol = Tolerances() if tol is None else tol
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers must be an integer >= 1, got {workers!r}")
    if scenes is not None:
        scenes = scenes.select(sensors, n)
        jobs: list[Any] = list(scenes.cases)
        counts = scenes.per_sensor()
        config = EvalConfig(
            parsed,
            scenes.sensors,
            max(counts.values(), default=0),
            scenes.seed,
            scenes.noise,
            tol,
            scenes.source,
            scenes.clutter,
        )
    else:
        chosen = check_sensors(sensors)
        n = DEFAULT_SCENES if n is None else n
        recipe = scene_recipe(chosen, n, seed, noise)
        jobs = [(s, i, seed, noise, bool(clutter)) for s, i in recipe]
        config = EvalConfig(parsed, chosen, n, seed, noise, tol, clutter=bool(clutter))
    records = [r for batch in _run_jobs(jobs, parsed, tol, workers, on_scene) for r in batch]
    return EvalResult(config, tuple(records), _summarise(records, config), scenes)


def _run_jobs(
    jobs: list[Any],
    specs: tuple[MethodSpec, ...],
    tol: Tolerances,
    workers: int,
    on_scene: OnScene | None,
) -> Iterator[list[ScanRecord]]:
    work = partial(_run_job, specs=specs, tol=tol)
    if workers == 1 or len(jobs) < 2:
        results: Iterable[list[ScanRecord]] = map(work, jobs)
        yield from _counted(results, len(jobs), on_scene)
        return
    from concurrent.futures import ProcessPoolExecutor

    chunk = max(1, len(jobs) // (8 * workers))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield from _counted(pool.map(work, jobs, chunksize=chunk), len(jobs), on_scene)


def _counted(
    results: Iterable[list[ScanRecord]], total: int, on_scene: OnScene | None
) -> Iterator[list[ScanRecord]]:
    for done, batch in enumerate(results, 1):
        if on_scene is not None:
            on_scene(done, total)
        yield batch


Runner = Callable[[SceneCase], Extraction]


@lru_cache(maxsize=32)
def _runner(spec: MethodSpec) -> Runner:
    """What ``spec`` does with a scene (one extractor per spec and process)."""
    if spec.is_truth:
        return _truth_row
    extractor = spec.extractor()
    return lambda case: extractor(case.scan)


def _truth_row(case: SceneCase) -> Extraction:
    """:func:`truth_extraction` of a scene, covariances from its preset's range noise."""
    sigma = get_sensor(case.sensor).noise.sigma if case.noise == "realistic" else 0.0
    return truth_extraction(case.scan, case.truth, range_sigma=sigma)


def extract_case(spec: MethodSpec, case: SceneCase) -> Extraction:
    """What ``spec`` finds in a scene: its extractor on the scan, or the truth row."""
    return _runner(spec)(case)


def _run_job(
    job: SceneCase | tuple[str, int, int, str, bool],
    *,
    specs: tuple[MethodSpec, ...],
    tol: Tolerances,
) -> list[ScanRecord]:
    """Score every spec on one scene (generated here from its recipe, or given).

    Every spec is timed on the scene's scan by :func:`~scanlines.bench.timing.time_calls`
    (one pass: an untimed extraction, then the timed one).
    """
    case = job if isinstance(job, SceneCase) else make_scene(*job)
    timed = time_calls({s.label: _runner(s) for s in specs}, [case])
    out = []
    for spec in specs:
        extraction = timed[spec.label].results[0]
        us = int(timed[spec.label].samples_ns[0, 0]) / 1000.0
        nonfinite = int(np.count_nonzero(~np.isfinite(extraction.lines).all(axis=1)))
        found = score(extraction, case.truth, case.scan, tol)
        out.append(
            ScanRecord(case.sensor, case.index, case.seed, case.kind, spec, us, nonfinite, found)
        )
    return out


def _summarise(records: list[ScanRecord], config: EvalConfig) -> tuple[SummaryRecord, ...]:
    groups = [*config.sensors, ALL_SENSORS] if len(config.sensors) > 1 else [*config.sensors]
    out = []
    for sensor in groups:
        for spec in config.specs:
            chosen = [
                r
                for r in records
                if r.spec.label == spec.label and sensor in (ALL_SENSORS, r.sensor)
            ]
            if chosen:
                us = np.array([r.us for r in chosen])
                out.append(
                    SummaryRecord(
                        sensor,
                        spec,
                        aggregate(r.score for r in chosen),
                        float(np.median(us)),
                        float(us.mean()),
                        sum(r.nonfinite_lines for r in chosen),
                    )
                )
    return tuple(out)
