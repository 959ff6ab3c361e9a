"""The paper's experiments (sec. 4), redone on the data scanlines ships: ``scanlines reproduce``.

Everything here runs on what the repository holds: the two real excerpts of
:mod:`scanlines.data` (Intel Research Lab, Freiburg 079), the hand labels of ten Intel
frames (:mod:`scanlines.data.labels`) and the scan simulator (:mod:`scanlines.sim`).
:func:`run` measures, :func:`render_markdown` writes ``RESULTS.md`` and
:func:`write_figures` its figures; :func:`reproduce` does all three.

What is measured
----------------
1. **Table 1** of the paper (breakpoints and corners of 10 Intel frames): on the
   hand-labelled Intel frames and on simulated Intel-like scans (``lms_1deg``), per
   frame and method, the actual and found counts, and matched precision and recall.
2. **Table 3** (counts, the paper's count-based accuracy rate, time per scan): on
   simulated scans of the paper's sensor (``tim571``) and on the labelled Intel frames,
   with matched precision and recall; on all shipped scans of both real excerpts
   (no labels): counts per scan, the environmental-similarity error and time.
3. **Fig. 13** (similarity error along the scan) for adaptive, IEPF and PDBS on one
   labelled Intel frame, the frame with each method's segments, and the paper's two
   headline claims measured on the same scans in one run: the similarity error of
   adaptive against IEPF (the paper: 8.3 % better) and the speed ratio (the paper: four
   times faster).
4. Every method on simulated ground truth for every sensor preset
   (:func:`scanlines.evaluate.evaluate`).

Matching
--------
Found events are matched one-to-one to true or labelled ones within
``Tolerances.event_beams`` beams (2), nearest pairs first (:func:`score_labelled`,
built on :func:`scanlines.metrics.score_events`). Uncertain hand labels are don't care:
a detection matched to one is neither a true nor a false positive, and missing one is
not a false negative. Simulated truth uses :func:`scanlines.metrics.score` with its own
don't-care rules (see :class:`~scanlines.metrics.Tolerances`).

Timing
------
All timings are taken in one process. Per dataset, one untimed pass runs every method on
every scan (its results are the ones scored, and it warms caches), then ``repeats``
timed passes follow, interleaved between methods (pass 1 of every method, then pass 2,
...); every call is one :func:`time.perf_counter_ns` sample. Reported: the median (and
90th percentile) of the samples, microseconds per scan; per scan, the median of its
samples. Section 4 uses :func:`~scanlines.evaluate.evaluate`'s own timing (one sample
per scan and method, each after an untimed extraction of the same scan by the same method).

``import scanlines.reproduce`` needs numpy only; the figures import matplotlib on use.
"""

from __future__ import annotations

import datetime as _dt
import gc
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from scanlines.errors import ParameterError
from scanlines.evaluate import EvalResult, MethodSpec, evaluate, make_scene, parse_specs
from scanlines.evaluate import tolerance_caption as sim_tolerance_caption
from scanlines.extraction import ALPHA, RHO, Extraction
from scanlines.extractor import method_names as registered_methods
from scanlines.io.writers import write_text_atomically
from scanlines.metrics import (
    EventScore,
    SimilarityScore,
    Tolerances,
    accuracy_rate,
    score,
    score_events,
)
from scanlines.scan import Scan
from scanlines.sim.sensors import SENSORS
from scanlines.sim.truth import Truth

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "FIG13_METHODS",
    "PAPER_SIMILARITY_GAIN",
    "PAPER_SPEED_RATIO",
    "Case",
    "DatasetRun",
    "FrameScore",
    "Headline",
    "LabelledFrameLike",
    "MethodSummary",
    "ReproduceConfig",
    "ReproduceResult",
    "default_specs",
    "headline",
    "label_tolerance_caption",
    "load_labels",
    "point_distances",
    "render_markdown",
    "reproduce",
    "run",
    "score_case",
    "score_labelled",
    "write_figures",
]

PAPER_SIMILARITY_GAIN = 8.3
"""The paper's claim: its method's similarity is 8.3 % better than IEPF's (sec. 4.4)."""

PAPER_SPEED_RATIO = 4.0
"""The paper's claim: its method is four times faster than IEPF (sec. 4.5, Table 3)."""

REFERENCE = "iepf"
"""The method the paper compares against; time ratios refer to it."""

FIG13_METHODS = ("adaptive", "iepf", "pdbs")
"""The methods of the paper's Fig. 13 (its method, IEPF, PDBS)."""

PAPER_BOUND = 0.02
"""The paper's bound on its method's similarity error, metres (sec. 4.4)."""

FIGURES = {
    "fig13": "fig13_similarity.png",
    "frame": "fig13_segments.png",
    "bars": "ground_truth_bars.png",
}
"""Figure files written into ``<out>/figures``."""

DPI = 100

Stage = Callable[[str], None]
"""``on_stage(text)``: called when a stage of :func:`run` starts."""


class LabelledFrameLike(Protocol):
    """What :func:`run` needs of a hand-labelled frame (``scanlines.data.labels``)."""

    scan: int
    breakpoints: tuple[int, ...]
    corners: tuple[int, ...]
    uncertain_breakpoints: tuple[int, ...]
    uncertain_corners: tuple[int, ...]


# --------------------------------------------------------------------------- configuration


@dataclass(frozen=True)
class ReproduceConfig:
    """What :func:`run` measures.

    Parameters
    ----------
    scenes_per_sensor:
        Simulated scenes per sensor preset for section 4.
    table_scenes:
        Simulated scenes for the Table 1 (``lms_1deg``) and Table 3 (``tim571``) analogues.
    frames:
        Labelled Intel frames used (the first ones); ``None``: all.
    real_scans:
        Scans of each real excerpt for the unlabelled Table 3 and the headline; ``None``:
        all shipped scans.
    repeats:
        Timed passes per dataset.
    seed:
        Base seed of the simulated scenes (:func:`scanlines.evaluate.scene_seed`).
    tol:
        Matching tolerances.
    quick:
        Recorded in the output (set by :meth:`quick_config`).
    """

    scenes_per_sensor: int = 100
    table_scenes: int = 10
    frames: int | None = None
    real_scans: int | None = None
    repeats: int = 5
    seed: int = 0
    tol: Tolerances = field(default_factory=Tolerances)
    quick: bool = False

    @classmethod
    def quick_config(cls, **changes: Any) -> ReproduceConfig:
        """A small run for tests: 3 scenes, 2 labelled frames, 20 real scans, 1 repeat."""
        base = cls(scenes_per_sensor=3, table_scenes=3, frames=2, real_scans=20, repeats=1)
        return replace(base, quick=True, **changes)

    def validated(self) -> ReproduceConfig:
        """This configuration, checked.

        Raises
        ------
        ParameterError
            For a count below 1 or a negative seed.
        """
        for name in ("scenes_per_sensor", "table_scenes", "repeats"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ParameterError(f"{name.replace('_', ' ')} must be an integer >= 1")
        for name in ("frames", "real_scans"):
            value = getattr(self, name)
            if value is not None and (not isinstance(value, int) or value < 1):
                raise ParameterError(f"{name.replace('_', ' ')} must be an integer >= 1")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ParameterError(f"seed must be an integer >= 0, got {self.seed!r}")
        return self


def default_specs() -> tuple[MethodSpec, ...]:
    """Every registered method with default parameters, and ``adaptive:paper`` after adaptive."""
    names: list[str] = []
    for name in registered_methods():
        names.append(name)
        if name == "adaptive":
            names.append("adaptive:paper")
    return parse_specs(names)


def load_labels() -> list[LabelledFrameLike]:
    """The hand labels of the shipped Intel frames (``scanlines.data.labels.intel_labels``).

    Raises
    ------
    ParameterError
        When the labels are not installed.
    """
    try:
        from scanlines.data.labels import intel_labels
    except ImportError as error:
        raise ParameterError(
            f"the Intel hand labels (scanlines.data.labels) are not available: {error}"
        ) from None
    return list(intel_labels())


def _label_metadata() -> tuple[str, str]:
    """The labelling rule and how the frames were chosen, as the label file states them."""
    try:
        from scanlines.data.labels import intel_label_set

        label_set = intel_label_set()
    except ImportError:
        return "", ""
    return str(label_set.rule), str(label_set.how_chosen)


# --------------------------------------------------------------------------- scoring


def score_labelled(
    found: Sequence[int] | np.ndarray,
    certain: Sequence[int] | np.ndarray,
    uncertain: Sequence[int] | np.ndarray = (),
    *,
    tolerance: int = 2,
    n_beams: int,
    circular: bool = False,
) -> EventScore:
    """Score found event indices against hand labels, uncertain labels being don't care.

    Found and labelled events (certain and uncertain together) are matched one-to-one
    within ``tolerance`` beams, nearest pairs first
    (:func:`scanlines.metrics.match_events`). A found event matched to a certain label is
    a true positive, one matched to an uncertain label is neither true nor false
    (``found_ignored``), one matching nothing is a false positive. A certain label left
    unmatched is a false negative; an uncertain one is not.
    """
    certain = np.asarray(certain, dtype=np.intp).reshape(-1)
    uncertain = np.asarray(uncertain, dtype=np.intp).reshape(-1)
    true = np.concatenate((certain, uncertain))
    dont_care = np.concatenate((np.zeros(len(certain), bool), np.ones(len(uncertain), bool)))
    return score_events(
        np.asarray(found, dtype=np.intp).reshape(-1),
        true,
        tolerance=tolerance,
        n_beams=n_beams,
        circular=circular,
        true_dont_care=dont_care,
    )


def label_tolerance_caption(tol: Tolerances) -> str:
    """How found events are scored against hand labels, for captions."""
    return (
        f"Matching: found and labelled events one-to-one within +-{tol.event_beams} beams, "
        "nearest pairs first, breakpoints with breakpoints and corners with corners; "
        "uncertain labels are don't care (a detection matched to one is neither TP nor FP, "
        "missing one is not FN). Actual counts and the accuracy rate use the certain "
        "labels only."
    )


@dataclass(frozen=True, eq=False)
class Case:
    """One scan to run the methods on, with its truth when there is one.

    Attributes
    ----------
    name:
        ``"intel #12"``, ``"tim571 #3"``...
    scan:
        The scan.
    truth:
        Simulator ground truth, or ``None``.
    labels:
        Hand labels, or ``None``.
    """

    name: str
    scan: Scan
    truth: Truth | None = None
    labels: LabelledFrameLike | None = None

    @property
    def truth_kind(self) -> str:
        """``"simulator"``, ``"labels"`` or ``"none"``."""
        if self.truth is not None:
            return "simulator"
        return "labels" if self.labels is not None else "none"


@dataclass(frozen=True)
class FrameScore:
    """One method on one scan.

    Attributes
    ----------
    frame:
        The case name.
    label:
        The method spec label.
    n_segments:
        Segments found.
    bp_found, c_found:
        Breakpoints and corners found.
    bp_actual, c_actual:
        True (simulator) or certain labelled counts; ``None`` without truth.
    bp_dont_care, c_dont_care:
        True events that are don't care (uncertain labels, or the simulator rules).
    bp, corners:
        Matched scores; ``None`` without truth.
    similarity:
        Environmental-similarity error sums over the segments with a finite line
        (:func:`line_similarity`).
    covered_points:
        Distinct beams on those segments.
    nonfinite_lines:
        Segments without a finite line (not in the similarity).
    valid_points:
        Valid returns of the scan.
    accuracy:
        The paper's count-based accuracy rate (NaN without truth).
    """

    frame: str
    label: str
    n_segments: int
    bp_found: int
    c_found: int
    bp_actual: int | None
    c_actual: int | None
    bp_dont_care: int
    c_dont_care: int
    bp: EventScore | None
    corners: EventScore | None
    similarity: SimilarityScore
    covered_points: int
    nonfinite_lines: int
    valid_points: int
    accuracy: float


def score_case(case: Case, label: str, extraction: Extraction, tol: Tolerances) -> FrameScore:
    """Score one extraction of ``case`` (simulator truth, hand labels, or similarity only)."""
    scan = case.scan
    bp_found, c_found = len(extraction.breakpoints), len(extraction.corners)
    similarity, covered, nonfinite = line_similarity(extraction, scan)
    common = {
        "frame": case.name,
        "label": label,
        "n_segments": len(extraction),
        "bp_found": bp_found,
        "c_found": c_found,
        "valid_points": int(np.count_nonzero(scan.valid)),
        "similarity": similarity,
        "covered_points": covered,
        "nonfinite_lines": nonfinite,
    }
    if case.truth is not None:
        s = score(extraction, case.truth, scan, tol)
        return FrameScore(
            **common,
            bp_actual=s.breakpoints.n_true,
            c_actual=s.corners.n_true,
            bp_dont_care=s.breakpoints.true_dont_care,
            c_dont_care=s.corners.true_dont_care,
            bp=s.breakpoints,
            corners=s.corners,
            accuracy=s.accuracy_rate,
        )
    if case.labels is None:
        return FrameScore(
            **common,
            bp_actual=None,
            c_actual=None,
            bp_dont_care=0,
            c_dont_care=0,
            bp=None,
            corners=None,
            accuracy=math.nan,
        )
    lab = case.labels
    events = {}
    for kind, found, certain, uncertain in (
        ("bp", extraction.breakpoints, lab.breakpoints, lab.uncertain_breakpoints),
        ("corners", extraction.corners, lab.corners, lab.uncertain_corners),
    ):
        events[kind] = score_labelled(
            found, certain, uncertain, tolerance=tol.event_beams, n_beams=len(scan)
        )
    bp_actual, c_actual = len(lab.breakpoints), len(lab.corners)
    return FrameScore(
        **common,
        bp_actual=bp_actual,
        c_actual=c_actual,
        bp_dont_care=len(lab.uncertain_breakpoints),
        c_dont_care=len(lab.uncertain_corners),
        bp=events["bp"],
        corners=events["corners"],
        accuracy=accuracy_rate(bp_found, bp_actual, c_found, c_actual),
    )


def point_distances(extraction: Extraction, scan: Scan) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per segment: its beams and their distances to its line (the paper's Fig. 13).

    The points are those :func:`scanlines.metrics.environmental_similarity` counts: the
    valid beams in ``first..last`` (across the seam when ``first > last``) that are not
    outliers. A segment without a finite line gets NaN distances.
    """
    n = len(scan)
    points = scan.points
    outliers = np.asarray(extraction.outliers, dtype=np.intp)
    out = []
    for k in range(len(extraction)):
        first, last = int(extraction.first[k]), int(extraction.last[k])
        beams = (first + np.arange((last - first) % n + 1)) % n
        beams = beams[scan.valid[beams] & ~np.isin(beams, outliers)]
        rho, alpha = extraction.lines[k, RHO], extraction.lines[k, ALPHA]
        p = points[beams]
        out.append((beams, np.abs(p[:, 0] * np.cos(alpha) + p[:, 1] * np.sin(alpha) - rho)))
    return out


def line_similarity(extraction: Extraction, scan: Scan) -> tuple[SimilarityScore, int, int]:
    """The similarity error over the segments that have a finite line.

    Returns the :class:`~scanlines.metrics.SimilarityScore` of those segments (equal to
    :func:`scanlines.metrics.environmental_similarity` when every line is finite), the
    number of distinct beams they cover, and the number of segments without a finite line
    (left out; the literal paper preset yields some on short segments).
    """
    pieces = point_distances(extraction, scan)
    finite = np.isfinite(extraction.lines).all(axis=1) if len(extraction) else np.zeros(0, bool)
    kept = [p for p, ok in zip(pieces, finite.tolist(), strict=True) if ok]
    d = np.concatenate([p[1] for p in kept]) if kept else np.zeros(0)
    covered = len(np.unique(np.concatenate([p[0] for p in kept]))) if kept else 0
    sim = SimilarityScore(
        n_points=len(d),
        sum_distance=float(d.sum()),
        sum_sq_distance=float((d * d).sum()),
        max_distance=float(d.max()) if len(d) else 0.0,
    )
    return sim, covered, int(np.count_nonzero(~finite))


# --------------------------------------------------------------------------- running


@dataclass(frozen=True)
class MethodSummary:
    """One method pooled over the scans of one dataset.

    Event scores and the similarity are summed over scans (micro-averages); counts are
    totals; times are the median and 90th percentile of all samples, microseconds.
    """

    label: str
    n_scans: int
    n_segments: int
    bp_found: int
    c_found: int
    bp_actual: int | None
    c_actual: int | None
    bp: EventScore | None
    corners: EventScore | None
    accuracy_mean: float
    accuracy_pooled: float
    similarity: SimilarityScore
    covered_points: int
    nonfinite_lines: int
    valid_points: int
    median_us: float
    p90_us: float

    @property
    def coverage(self) -> float:
        """Share of valid returns on a segment with a finite line (seen by the similarity)."""
        return self.covered_points / self.valid_points if self.valid_points else math.nan


@dataclass(frozen=True, eq=False)
class DatasetRun:
    """Every method on every scan of one dataset: extractions, scores and timings.

    Attributes
    ----------
    name:
        Short name (``"intel-labelled"``, ``"sim:tim571"``, ``"freiburg"``...).
    title:
        What the scans are.
    cases:
        The scans (with their truth).
    specs:
        The method specs.
    extractions:
        ``label -> one extraction per case`` (from the untimed pass).
    scores:
        ``label -> one score per case``.
    samples_ns:
        ``label -> (repeats, cases)`` timing samples, nanoseconds.
    """

    name: str
    title: str
    cases: tuple[Case, ...]
    specs: tuple[MethodSpec, ...]
    extractions: dict[str, list[Extraction]]
    scores: dict[str, list[FrameScore]]
    samples_ns: dict[str, np.ndarray]

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(s.label for s in self.specs)

    @property
    def truth_kind(self) -> str:
        return self.cases[0].truth_kind if self.cases else "none"

    def per_scan_us(self, label: str) -> np.ndarray:
        """Median time of every scan, microseconds."""
        return np.median(self.samples_ns[label], axis=0) / 1000.0

    def summary(self, label: str) -> MethodSummary:
        """The pooled scores and times of ``label``."""
        rows = self.scores[label]
        us = self.samples_ns[label].ravel() / 1000.0
        has_truth = rows[0].bp is not None
        rates = np.array([r.accuracy for r in rows], dtype=np.float64)
        finite = rates[np.isfinite(rates)]
        bp_actual = sum(r.bp_actual or 0 for r in rows) if has_truth else None
        c_actual = sum(r.c_actual or 0 for r in rows) if has_truth else None
        diff = sum(
            abs(r.bp_found - (r.bp_actual or 0)) + abs(r.c_found - (r.c_actual or 0)) for r in rows
        )
        total = (bp_actual or 0) + (c_actual or 0)
        return MethodSummary(
            label=label,
            n_scans=len(rows),
            n_segments=sum(r.n_segments for r in rows),
            bp_found=sum(r.bp_found for r in rows),
            c_found=sum(r.c_found for r in rows),
            bp_actual=bp_actual,
            c_actual=c_actual,
            bp=sum((r.bp for r in rows if r.bp is not None), EventScore()) if has_truth else None,
            corners=sum((r.corners for r in rows if r.corners is not None), EventScore())
            if has_truth
            else None,
            accuracy_mean=float(finite.mean()) if finite.size else math.nan,
            accuracy_pooled=1.0 - diff / total if has_truth and total else math.nan,
            similarity=sum((r.similarity for r in rows), SimilarityScore()),
            covered_points=sum(r.covered_points for r in rows),
            nonfinite_lines=sum(r.nonfinite_lines for r in rows),
            valid_points=sum(r.valid_points for r in rows),
            median_us=float(np.median(us)) if us.size else math.nan,
            p90_us=float(np.percentile(us, 90)) if us.size else math.nan,
        )

    def time_ratio(self, label: str, reference: str = REFERENCE) -> float:
        """Median time of ``label`` over that of ``reference`` (below 1: faster)."""
        if reference not in self.samples_ns:
            return math.nan
        return self.summary(label).median_us / self.summary(reference).median_us


def run_dataset(
    name: str,
    title: str,
    cases: Sequence[Case],
    specs: Sequence[MethodSpec],
    *,
    repeats: int,
    tol: Tolerances,
) -> DatasetRun:
    """Run, time and score every spec on every case (see the module docstring, Timing)."""
    if not cases:
        raise ParameterError(f"dataset {name} has no scans")
    extractors = {s.label: s.extractor() for s in specs}
    extractions = {label: [ex(c.scan) for c in cases] for label, ex in extractors.items()}
    gc.collect()
    clock = time.perf_counter_ns
    samples = {label: np.zeros((repeats, len(cases)), np.int64) for label in extractors}
    for r in range(repeats):
        for label, ex in extractors.items():
            row = samples[label][r]
            for i, case in enumerate(cases):
                start = clock()
                ex(case.scan)
                row[i] = clock() - start
    scores = {
        label: [score_case(c, label, e, tol) for c, e in zip(cases, found, strict=True)]
        for label, found in extractions.items()
    }
    return DatasetRun(name, title, tuple(cases), tuple(specs), extractions, scores, samples)


@dataclass(frozen=True)
class Headline:
    """The paper's two claims, measured on one dataset in one run.

    Attributes
    ----------
    dataset:
        Dataset name.
    n_scans:
        Scans measured.
    method, reference:
        Spec labels compared (``adaptive`` against ``iepf``).
    similarity_mm, reference_similarity_mm:
        Mean point-to-line distance (environmental similarity error) over all points of
        all segments of all scans, millimetres.
    similarity_gain_pct:
        ``100 (reference - method) / reference``: how much smaller the method's error is
        (positive: the method is better; the paper claims +8.3 %).
    median_us, reference_median_us:
        Median time per scan, microseconds.
    speed_ratio:
        ``reference time / method time``: above 1 the method is faster (the paper
        claims 4).
    """

    dataset: str
    n_scans: int
    method: str
    reference: str
    similarity_mm: float
    reference_similarity_mm: float
    similarity_gain_pct: float
    median_us: float
    reference_median_us: float
    speed_ratio: float


def headline(run: DatasetRun, method: str = "adaptive", reference: str = REFERENCE) -> Headline:
    """Similarity gain (%) and speed ratio of ``method`` against ``reference`` on ``run``."""
    a, b = run.summary(method), run.summary(reference)
    sim_a, sim_b = 1000 * a.similarity.mean, 1000 * b.similarity.mean
    return Headline(
        dataset=run.name,
        n_scans=len(run.cases),
        method=method,
        reference=reference,
        similarity_mm=sim_a,
        reference_similarity_mm=sim_b,
        similarity_gain_pct=100.0 * (sim_b - sim_a) / sim_b if sim_b else math.nan,
        median_us=a.median_us,
        reference_median_us=b.median_us,
        speed_ratio=b.median_us / a.median_us if a.median_us else math.nan,
    )


@dataclass(frozen=True, eq=False)
class ReproduceResult:
    """Everything one :func:`run` measured."""

    config: ReproduceConfig
    specs: tuple[MethodSpec, ...]
    labelled: DatasetRun
    sim_table1: DatasetRun
    sim_table3: DatasetRun
    real: tuple[DatasetRun, ...]
    ground_truth: EvalResult
    fig13_frame: int
    machine: dict[str, Any]
    started: str
    elapsed_s: float
    command: str
    label_notes: dict[int, str] = field(default_factory=dict)
    label_rule: str = ""
    label_how_chosen: str = ""

    def headlines(self, method: str = "adaptive") -> list[Headline]:
        """:func:`headline` of ``method`` on every real excerpt."""
        return [headline(r, method) for r in self.real]


def _sim_cases(sensor: str, n: int, seed: int) -> list[Case]:
    out = []
    for i in range(n):
        scene = make_scene(sensor, i, seed)
        out.append(Case(f"{sensor} #{i}", scene.scan, truth=scene.truth))
    return out


def _real_scans(name: str) -> list[Scan]:
    from scanlines.data import sample
    from scanlines.io import open_log

    return list(open_log(sample(name)))


FIG13_RULE = (
    "the labelled frame with the most certain corners, then the most certain breakpoints, "
    "then the lowest scan index"
)
"""How :func:`run` picks the Fig. 13 frame."""


def _choose_fig13_frame(labels: Sequence[LabelledFrameLike]) -> int:
    """The frame :data:`FIG13_RULE` picks."""
    best = max(labels, key=lambda f: (len(f.corners), len(f.breakpoints), -f.scan))
    return int(best.scan)


def run(
    config: ReproduceConfig | None = None,
    *,
    labels: Sequence[LabelledFrameLike] | None = None,
    specs: Sequence[str | MethodSpec] | None = None,
    command: str = "scanlines reproduce",
    on_stage: Stage | None = None,
) -> ReproduceResult:
    """Measure everything ``RESULTS.md`` shows (see the module docstring).

    Parameters
    ----------
    config:
        What to measure; :class:`ReproduceConfig` defaults when ``None``.
    labels:
        Hand-labelled Intel frames; :func:`load_labels` when ``None``.
    specs:
        Method specs; :func:`default_specs` when ``None`` (must include ``adaptive``,
        ``iepf`` and ``pdbs``).
    command:
        The command line recorded in the output.
    on_stage:
        Called with a short text when a stage starts.

    Raises
    ------
    ParameterError
        For a bad configuration, missing labels, a label outside the Intel excerpt or
        specs without adaptive, iepf and pdbs.
    """
    from scanlines.bench import machine_info

    config = (config or ReproduceConfig()).validated()
    parsed = default_specs() if specs is None else parse_specs(specs)
    missing = [m for m in FIG13_METHODS if m not in {s.label for s in parsed}]
    if missing:
        raise ParameterError(f"the specs must include {', '.join(missing)}")
    stage = on_stage or (lambda _text: None)
    started = _dt.datetime.now(_dt.UTC).replace(microsecond=0)
    t0 = time.perf_counter()
    machine = machine_info()
    tol = config.tol

    rule = how_chosen = ""
    if labels is None:
        frames = load_labels()
        rule, how_chosen = _label_metadata()
    else:
        frames = list(labels)
    if not frames:
        raise ParameterError("no labelled Intel frames")
    frames = sorted(frames, key=lambda f: f.scan)[: config.frames]
    intel = _real_scans("intel")
    for f in frames:
        if not 0 <= f.scan < len(intel):
            raise ParameterError(
                f"labelled frame {f.scan} is outside the Intel excerpt (0..{len(intel) - 1})"
            )
    label_notes = {int(f.scan): str(getattr(f, "notes", "") or "") for f in frames}

    stage(f"Table 1: {len(frames)} labelled Intel frames")
    labelled = run_dataset(
        "intel-labelled",
        "hand-labelled frames of the shipped Intel excerpt (SICK LMS, 180 beams at 1 deg)",
        [Case(f"intel #{f.scan}", intel[f.scan], labels=f) for f in frames],
        parsed,
        repeats=config.repeats,
        tol=tol,
    )
    stage(f"Table 1: {config.table_scenes} simulated lms_1deg scenes")
    sim_table1 = run_dataset(
        "sim:lms_1deg",
        "simulated Intel-like scans (lms_1deg preset), simulator ground truth",
        _sim_cases("lms_1deg", config.table_scenes, config.seed),
        parsed,
        repeats=config.repeats,
        tol=tol,
    )
    stage(f"Table 3: {config.table_scenes} simulated tim571 scenes")
    sim_table3 = run_dataset(
        "sim:tim571",
        "simulated scans of the paper's sensor (tim571 preset: 481 beams at 1/3 deg), "
        "simulator ground truth",
        _sim_cases("tim571", config.table_scenes, config.seed),
        parsed,
        repeats=config.repeats,
        tol=tol,
    )
    real = []
    titles = {
        "intel": "Intel Research Lab excerpt (SICK LMS, 180 beams at 1 deg), no labels",
        "freiburg": "Freiburg 079 excerpt (SICK LMS, 360 beams at 0.5 deg), no labels",
    }
    for name in ("intel", "freiburg"):
        scans = intel if name == "intel" else _real_scans(name)
        scans = scans[: config.real_scans]
        stage(f"Table 3 and headline: {len(scans)} {name} scans x {config.repeats} repeats")
        real.append(
            run_dataset(
                name,
                titles[name],
                [Case(f"{name} #{i}", s) for i, s in enumerate(scans)],
                parsed,
                repeats=config.repeats,
                tol=tol,
            )
        )
    stage(f"Ground truth: {config.scenes_per_sensor} scenes x {len(SENSORS)} sensor presets")
    ground_truth = evaluate(parsed, None, config.scenes_per_sensor, config.seed, tol=tol)
    try:
        machine["loadavg_after"] = [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        machine["loadavg_after"] = None
    return ReproduceResult(
        config=config,
        specs=parsed,
        labelled=labelled,
        sim_table1=sim_table1,
        sim_table3=sim_table3,
        real=tuple(real),
        ground_truth=ground_truth,
        fig13_frame=_choose_fig13_frame(frames),
        machine=machine,
        started=started.isoformat(),
        elapsed_s=time.perf_counter() - t0,
        command=command,
        label_notes=label_notes,
        label_rule=rule,
        label_how_chosen=how_chosen,
    )


# --------------------------------------------------------------------------- figures


def _fig13_case(result: ReproduceResult) -> tuple[int, Case]:
    run_ = result.labelled
    for i, case in enumerate(run_.cases):
        if case.labels is not None and int(case.labels.scan) == result.fig13_frame:
            return i, case
    raise KeyError(result.fig13_frame)


def plot_fig13(result: ReproduceResult) -> Figure:
    """Similarity error along the scan for :data:`FIG13_METHODS` on the chosen frame."""
    from scanlines.plot import SEGMENT_COLOURS, _pyplot

    plt = _pyplot()
    i, case = _fig13_case(result)
    n = len(case.scan)
    fig, axes = plt.subplots(len(FIG13_METHODS), 1, figsize=(8, 6.2), sharex=True, sharey=True)
    top = 0.0
    for ax, label in zip(axes, FIG13_METHODS, strict=True):
        extraction = result.labelled.extractions[label][i]
        pieces = point_distances(extraction, case.scan)
        for k, (beams, d) in enumerate(pieces):
            if beams.size:
                order = np.argsort(beams, kind="stable")
                ax.plot(
                    beams[order],
                    100 * d[order],
                    ".-",
                    ms=3,
                    lw=0.8,
                    c=SEGMENT_COLOURS[k % len(SEGMENT_COLOURS)],
                )
                if np.isfinite(d).any():
                    top = max(top, float(100 * np.nanmax(d)))
        ax.axhline(100 * PAPER_BOUND, ls="--", lw=0.8, c="#d62728")
        sim = result.labelled.scores[label][i].similarity
        ax.set_title(
            f"{label}: {len(extraction)} segments, mean {1000 * sim.mean:.1f} mm, "
            f"max {1000 * sim.max_distance:.1f} mm, {sim.n_points} points",
            fontsize=9,
        )
        ax.set_ylabel("distance (cm)", fontsize=8)
        ax.grid(True, lw=0.3)
        ax.tick_params(labelsize=8)
    axes[-1].set_xlabel("beam index", fontsize=8)
    axes[-1].set_xlim(-1, n)
    axes[0].set_ylim(0, max(3.0, min(top * 1.05, 30.0)))
    fig.suptitle(
        f"Similarity error along Intel frame {result.fig13_frame} (shipped excerpt): distance "
        "of each point to its segment's line; one colour per segment; dashed: 2 cm",
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def plot_fig13_frame(result: ReproduceResult) -> Figure:
    """The chosen frame with each Fig. 13 method's segments and the hand labels."""
    from scanlines.evaluate import TRUTH_MARK
    from scanlines.plot import _pyplot, plot_extraction

    plt = _pyplot()
    i, case = _fig13_case(result)
    lab = case.labels
    points = case.scan.points
    fig, axes = plt.subplots(1, len(FIG13_METHODS), figsize=(4.2 * len(FIG13_METHODS), 4.6))
    for ax, label in zip(axes, FIG13_METHODS, strict=True):
        extraction = result.labelled.extractions[label][i]
        for beams, marker, name in (
            (lab.breakpoints, "o", "labelled breakpoints"),
            (lab.corners, "D", "labelled corners"),
        ):
            if len(beams):
                ax.plot(
                    *points[np.asarray(beams, np.intp)].T,
                    marker,
                    ms=10,
                    c=TRUTH_MARK,
                    alpha=0.5,
                    ls="none",
                    zorder=0,
                    label=name,
                )
        plot_extraction(case.scan, extraction, ax, title=label, legend=False)
        ax.tick_params(labelsize=7)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle(
        f"Intel frame {result.fig13_frame}: segments, breakpoints (red triangles) and corners "
        "(black squares) found; amber: certain hand labels",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


BAR_COLOURS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
"""One colour per method in :func:`plot_ground_truth_bars` (matplotlib's tab10)."""


def plot_ground_truth_bars(ev: EvalResult) -> Figure:
    """Section 4 as bars: one panel per sensor preset, :data:`~scanlines.evaluate.BAR_METRICS`
    by method, one distinct colour per method (up to 10)."""
    from scanlines.evaluate import BAR_METRICS
    from scanlines.plot import _pyplot

    plt = _pyplot()
    sensors = [s for s in dict.fromkeys(r.sensor for r in ev.summaries) if s != "all"]
    specs = ev.config.specs
    cols = 2 if len(sensors) > 1 else 1
    rows = -(-len(sensors) // cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.2 * cols, 3.0 * rows + 1.2), squeeze=False, sharey=True
    )
    x = np.arange(len(BAR_METRICS))
    width = 0.85 / len(specs)
    for ax, sensor in zip(axes.flat, sensors, strict=False):
        for j, spec in enumerate(specs):
            summary = ev.summary(sensor, spec.label).summary
            ax.bar(
                x + (j - (len(specs) - 1) / 2) * width,
                [fn(summary) for _, fn in BAR_METRICS],
                width,
                label=spec.label,
                color=BAR_COLOURS[j % len(BAR_COLOURS)],
            )
        n_scans = ev.summary(sensor, specs[0].label).summary.n_scans
        ax.set_title(f"{sensor} ({n_scans} scans)", fontsize=9)
        ax.set_xticks(x, [name for name, _ in BAR_METRICS], fontsize=8)
        ax.set_ylim(0, 1.05)
        ax.tick_params(labelsize=8)
        ax.grid(True, axis="y", lw=0.3)
    for ax in list(axes.flat)[len(sensors) :]:
        ax.axis("off")
    for ax in axes[:, 0]:
        ax.set_ylabel("rate (FalsePos: lower is better)", fontsize=8)
    handles, names = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=min(len(specs), 5), fontsize=8)
    height = 3.0 * rows + 1.2
    fig.suptitle(sim_tolerance_caption(ev.config.tol), fontsize=7)
    fig.tight_layout(rect=(0, 0.75 / height, 1, 1))
    return fig


def write_figures(result: ReproduceResult, folder: str | Path) -> dict[str, Path]:
    """Write the figures (:data:`FIGURES`) into ``folder``; returns key -> path."""
    from scanlines.plot import save

    folder = Path(folder)
    return {
        "fig13": save(plot_fig13(result), folder / FIGURES["fig13"], dpi=DPI),
        "frame": save(plot_fig13_frame(result), folder / FIGURES["frame"], dpi=DPI),
        "bars": save(
            plot_ground_truth_bars(result.ground_truth), folder / FIGURES["bars"], dpi=DPI
        ),
    }


# --------------------------------------------------------------------------- markdown


def _f(value: float | None, fmt: str = ".2f") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return format(value, fmt)


def _us(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{value:,.0f}"


def _pct(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{100 * value:.1f} %"


def _table(columns: Sequence[str], rows: Sequence[Sequence[str]], left: int = 1) -> str:
    def cell(text: str) -> str:
        return str(text).replace("|", "\\|")

    lines = ["| " + " | ".join(cell(c) for c in columns) + " |"]
    lines.append("|" + "|".join(":---" if i < left else "---:" for i in range(len(columns))) + "|")
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _machine_line(result: ReproduceResult) -> str:
    m = result.machine
    cores = f"{m.get('cores_logical')} logical cores"
    if m.get("cores_usable") is not None:
        cores += f" ({m['cores_usable']} usable)"
    load, after = m.get("loadavg_before"), m.get("loadavg_after")
    load_text = f"; 1-min load average {load[0]:.2f} at the start" if load else ""
    if load and after:
        load_text += f", {after[0]:.2f} at the end"
    return (
        f"**Machine (every time below):** {m.get('cpu')}, {cores}, {m.get('platform')}, "
        f"{m.get('python')}, numpy {m.get('numpy')}{load_text}. All times were measured in "
        "this one process: per dataset one untimed pass over every scan (its results are the "
        f"ones scored; it also warms caches), then {result.config.repeats} timed pass"
        f"{'es' if result.config.repeats != 1 else ''} interleaved between methods; "
        "us/scan is the median of all samples (`time.perf_counter_ns`). Section 4 uses "
        "`scanlines.evaluate`'s timing: one sample per scan and method, each after an untimed "
        "extraction of the same scan by the same method."
    )


def _event_pr(s: EventScore | None) -> tuple[str, str]:
    if s is None:
        return "-", "-"
    return _f(s.precision), _f(s.recall)


def _table1(run_: DatasetRun, tol_text: str, dont_care: str) -> str:
    labels = run_.labels
    first = run_.scores[labels[0]]
    rows = []
    for j, case in enumerate(run_.cases):
        f = first[j]
        cells = [
            case.name,
            str(f.bp_actual),
            str(f.c_actual),
            f"{f.bp_dont_care} / {f.c_dont_care}",
        ]
        cells += [
            f"{run_.scores[lab][j].bp_found} / {run_.scores[lab][j].c_found}" for lab in labels
        ]
        rows.append(cells)
    totals = [run_.summary(lab) for lab in labels]
    rows.append(
        [
            "**total**",
            str(sum(f.bp_actual or 0 for f in first)),
            str(sum(f.c_actual or 0 for f in first)),
            f"{sum(f.bp_dont_care for f in first)} / {sum(f.c_dont_care for f in first)}",
            *[f"{t.bp_found} / {t.c_found}" for t in totals],
        ]
    )
    counts = _table(
        [
            "frame",
            "actual bp",
            "actual corners",
            f"{dont_care} bp / c",
            *[f"{lab} bp / c" for lab in labels],
        ],
        rows,
    )
    pooled_rows = []
    for t in totals:
        bp, c = t.bp or EventScore(), t.corners or EventScore()
        pooled_rows.append(
            [
                t.label,
                str(t.bp_found),
                f"{bp.tp} / {bp.fp} / {bp.fn}",
                *_event_pr(t.bp),
                _f(bp.f1),
                str(t.c_found),
                f"{c.tp} / {c.fp} / {c.fn}",
                *_event_pr(t.corners),
                _f(c.f1),
                _f(t.accuracy_mean, ".3f"),
            ]
        )
    pooled = _table(
        [
            "method",
            "bp found",
            "bp TP / FP / FN",
            "bp P",
            "bp R",
            "bp F1",
            "corners found",
            "corner TP / FP / FN",
            "corner P",
            "corner R",
            "corner F1",
            "accuracy rate",
        ],
        pooled_rows,
    )
    detail_rows = []
    for j, case in enumerate(run_.cases):
        for lab in labels:
            f = run_.scores[lab][j]
            detail_rows.append(
                [
                    case.name,
                    lab,
                    f"{f.bp_found} / {f.bp_actual}",
                    *_event_pr(f.bp),
                    f"{f.c_found} / {f.c_actual}",
                    *_event_pr(f.corners),
                    _f(f.accuracy, ".3f"),
                ]
            )
    detail = _table(
        [
            "frame",
            "method",
            "bp found / actual",
            "bp P",
            "bp R",
            "corners found / actual",
            "corner P",
            "corner R",
            "accuracy rate",
        ],
        detail_rows,
        left=2,
    )
    return "\n".join(
        [
            "Counts per frame (found: `breakpoints / corners`):\n",
            counts,
            f"Matched, pooled over the {len(run_.cases)} frames (P = TP / (TP + FP), "
            "R = TP / (TP + FN); accuracy rate: the paper's count-based rate, mean over "
            f"frames). {tol_text}\n",
            pooled,
            "<details><summary>Per frame and method: matched precision and recall</summary>\n",
            tol_text + "\n",
            detail,
            "</details>\n",
        ]
    )


def _table3_truth(run_: DatasetRun, tol_text: str) -> str:
    rows = []
    for lab in run_.labels:
        t = run_.summary(lab)
        rows.append(
            [
                lab,
                f"{t.bp_found} / {t.bp_actual}",
                f"{t.c_found} / {t.c_actual}",
                _f(t.accuracy_mean, ".3f"),
                *_event_pr(t.bp),
                *_event_pr(t.corners),
                _f(1000 * t.similarity.mean, ".1f"),
                _us(t.median_us),
                _f(run_.time_ratio(lab)),
            ]
        )
    table = _table(
        [
            "method",
            "bp found / actual",
            "corners found / actual",
            "accuracy rate",
            "bp P",
            "bp R",
            "corner P",
            "corner R",
            "sim. error mm",
            "us/scan",
            "time / iepf",
        ],
        rows,
    )
    return (
        f"{len(run_.cases)} scans: {run_.title}. Found and actual counts are totals over the "
        "scans; accuracy rate: the paper's `1 - (|bp found - bp actual| + |c found - c "
        "actual|) / (bp actual + c actual)`, mean over scans (it compares counts only, so a "
        "detection in the wrong place is not seen); P and R: matched, pooled over scans; "
        "sim. error: mean point-to-line distance; us/scan: median; time / iepf: below 1 is "
        f"faster than iepf. {tol_text}\n\n" + table
    )


def _table3_paper_layout(run_: DatasetRun, method: str = "adaptive") -> str:
    rows = []
    ours, ref = run_.scores[method], run_.scores[REFERENCE]
    us_m, us_r = run_.per_scan_us(method), run_.per_scan_us(REFERENCE)
    for j, case in enumerate(run_.cases):
        a, b = ours[j], ref[j]
        rows.append(
            [
                case.name,
                str(a.bp_actual),
                str(a.c_actual),
                str(b.bp_found),
                str(a.bp_found),
                str(b.c_found),
                str(a.c_found),
                _pct(b.accuracy),
                _pct(a.accuracy),
                f"{us_r[j] / 1000:.2f}",
                f"{us_m[j] / 1000:.2f}",
            ]
        )
    return _table(
        [
            "scan",
            "actual bp",
            "actual corners",
            "bp IEPF",
            f"bp {method}",
            "corners IEPF",
            f"corners {method}",
            "accuracy IEPF",
            f"accuracy {method}",
            "ms IEPF",
            f"ms {method}",
        ],
        rows,
    )


def _table3_real(run_: DatasetRun) -> str:
    n = len(run_.cases)
    rows = []
    for lab in run_.labels:
        t = run_.summary(lab)
        rows.append(
            [
                lab,
                _f(t.bp_found / n, ".1f"),
                _f(t.c_found / n, ".1f"),
                _f(t.n_segments / n, ".1f"),
                _f(1000 * t.similarity.mean, ".2f"),
                _f(1000 * t.similarity.rms, ".2f"),
                _pct(t.coverage),
                _us(t.median_us),
                _us(t.p90_us),
                _f(run_.time_ratio(lab)),
            ]
        )
    return _table(
        [
            "method",
            "bp / scan",
            "corners / scan",
            "segments / scan",
            "sim. error mm",
            "sim. RMS mm",
            "points on segments",
            "us/scan",
            "p90 us/scan",
            "time / iepf",
        ],
        rows,
    )


def _lower_higher(gain_pct: float) -> str:
    if not math.isfinite(gain_pct):
        return "-"
    return f"{abs(gain_pct):.1f} % {'lower' if gain_pct >= 0 else 'higher'}"


def _nonfinite_note(run_: DatasetRun) -> str:
    parts = []
    for lab in run_.labels:
        t = run_.summary(lab)
        if t.nonfinite_lines:
            parts.append(
                f"{lab}: {t.nonfinite_lines} of {t.n_segments} segments "
                f"({100 * t.nonfinite_lines / t.n_segments:.0f} %)"
            )
    if not parts:
        return ""
    return (
        "Segments without a finite line are left out of the similarity error and of the "
        f"points on segments ({run_.name}: {'; '.join(parts)}).\n"
    )


def _verdict_similarity(h: Headline) -> str:
    g = h.similarity_gain_pct
    if not math.isfinite(g):
        return "cannot be computed"
    if g >= PAPER_SIMILARITY_GAIN:
        return f"reproduces: the error is {g:.1f} % lower (paper: {PAPER_SIMILARITY_GAIN} %)"
    if g > 0:
        return (
            f"same direction, smaller: the error is {g:.1f} % lower "
            f"(paper: {PAPER_SIMILARITY_GAIN} %)"
        )
    return f"does not reproduce: the error is {-g:.1f} % higher than IEPF's"


def _verdict_speed(h: Headline) -> str:
    r = h.speed_ratio
    if not math.isfinite(r):
        return "cannot be computed"
    if r >= PAPER_SPEED_RATIO:
        return f"reproduces: {r:.2f}x faster than IEPF (paper: 4x)"
    if r > 1:
        return f"faster, but not 4x: {r:.2f}x faster than IEPF"
    return f"does not reproduce: {1 / r:.2f}x slower than IEPF (paper: 4x faster)"


def _headline_section(result: ReproduceResult) -> str:
    n_real = len(result.real[0].cases)
    scans_text = (
        f"all {n_real} shipped scans of each real excerpt"
        if result.config.real_scans is None
        else f"the first {n_real} scans of each real excerpt"
    )
    rows = []
    for run_ in result.real:
        for lab in ("adaptive", "adaptive:paper", REFERENCE):
            if lab not in run_.scores:
                continue
            t = run_.summary(lab)
            h = headline(run_, lab)
            n = len(run_.cases)
            rows.append(
                [
                    run_.name,
                    lab,
                    str(n),
                    _f(h.similarity_mm, ".2f"),
                    "-" if lab == REFERENCE else _lower_higher(h.similarity_gain_pct),
                    _pct(t.coverage),
                    _f(t.n_segments / n, ".1f"),
                    _us(h.median_us),
                    "-" if lab == REFERENCE else f"{h.speed_ratio:.2f}",
                ]
            )
    table = _table(
        [
            "excerpt",
            "method",
            "scans",
            "sim. error mm",
            "error vs IEPF",
            "points on segments",
            "segments / scan",
            "us/scan",
            "speed vs IEPF (IEPF time / time)",
        ],
        rows,
        left=2,
    )
    lines = []
    for h in result.headlines("adaptive"):
        lines.append(
            f"- **{h.dataset}** ({h.n_scans} scans), adaptive (default) vs iepf: similarity "
            f"error {h.similarity_mm:.2f} mm vs {h.reference_similarity_mm:.2f} mm, "
            f"{_verdict_similarity(h)}; time {h.median_us:,.0f} us vs "
            f"{h.reference_median_us:,.0f} us per scan, {_verdict_speed(h)}."
        )
    for h in (
        result.headlines("adaptive:paper") if "adaptive:paper" in result.labelled.scores else []
    ):
        lines.append(
            f"- **{h.dataset}**, adaptive:paper (the paper's text, literally) vs iepf: "
            f"{_verdict_similarity(h)}; {_verdict_speed(h)}."
        )
    return "\n".join(
        [
            "## Headline: the paper's two claims, measured\n",
            "The paper (sec. 4.4, 4.5 and Conclusions): its method's environmental similarity "
            f"is {PAPER_SIMILARITY_GAIN} % better than IEPF's, and it is four times faster "
            "than IEPF (4.6-9.2 ms against 19.4-39.7 ms per scan, MATLAB 2016b, Core "
            "i5-6300U). Here both are measured in the same run on the same scans: "
            f'{scans_text}. "Better similarity" is read as a smaller '
            "mean perpendicular distance of the points to their segment's line (the paper's "
            "Fig. 13 measure), pooled over all points of all segments of all scans.\n",
            *lines,
            "",
            table,
            "Read the similarity error with the coverage next to it: the measure only sees "
            "points that lie on a segment, so a method that drops more points (outliers, "
            "short clusters) or cuts walls into more, shorter segments scores lower without "
            "describing the room better. It needs no ground truth, which is why the matched "
            "scores of Tables 1 and 3 are the stronger evidence. The times compare our "
            "implementations, not the paper's MATLAB code: adaptive, iepf, pdbs and "
            "split_merge run as compiled kernels (numba), the other methods as numpy (see "
            "`docs/PERFORMANCE.md`).\n",
            *[_nonfinite_note(r) for r in result.real if _nonfinite_note(r)],
        ]
    )


def _fig13_section(result: ReproduceResult, figures: dict[str, str]) -> str:
    i, case = _fig13_case(result)
    rows = []
    for lab in FIG13_METHODS:
        f = result.labelled.scores[lab][i]
        pieces = point_distances(result.labelled.extractions[lab][i], case.scan)
        d = np.concatenate([p[1] for p in pieces]) if pieces else np.zeros(0)
        d = d[np.isfinite(d)]
        over = float(np.mean(d > PAPER_BOUND)) if d.size else math.nan
        rows.append(
            [
                lab,
                str(f.n_segments),
                str(f.similarity.n_points),
                _f(1000 * f.similarity.mean, ".2f"),
                _f(1000 * f.similarity.max_distance, ".1f"),
                _pct(over),
                f"{f.bp_found} / {f.bp_actual}",
                f"{f.c_found} / {f.c_actual}",
            ]
        )
    note = result.label_notes.get(result.fig13_frame, "")
    return "\n".join(
        [
            "## 3. Fig. 13 analogue: similarity error along one real frame\n",
            f'Frame: Intel excerpt scan {result.fig13_frame} (`list(open_log(sample("intel")))'
            f"[{result.fig13_frame}]`), {FIG13_RULE}."
            + (f" Label notes: {note}" if note else "")
            + " The paper's "
            "Fig. 13 shows the same curve for its own indoor scan (TiM571); its method stays "
            "under 2 cm.\n",
            f"![similarity error along the scan](figures/{figures['fig13']})\n",
            f"![the frame with each method's segments](figures/{figures['frame']})\n",
            _table(
                [
                    "method",
                    "segments",
                    "points",
                    "mean mm",
                    "max mm",
                    "points > 2 cm",
                    "bp found / labelled",
                    "corners found / labelled",
                ],
                rows,
            ),
            "Distance: perpendicular distance of each point to the line of its segment "
            "(valid beams in the segment's index range, outliers excluded). Labelled counts "
            f"are certain labels. {label_tolerance_caption(result.config.tol)}\n",
        ]
    )


def _ground_truth_section(result: ReproduceResult, figures: dict[str, str]) -> str:
    ev = result.ground_truth
    cfg = ev.config
    rows = []
    for rec in ev.summaries:
        if rec.sensor == "all":
            continue
        s = rec.summary
        rows.append(
            [
                rec.sensor,
                rec.spec.label,
                _f(s.breakpoints.f1, ".3f"),
                _f(s.corners.f1, ".3f"),
                _f(s.segments.true_pos, ".3f"),
                _f(s.segments.false_pos, ".3f"),
                _us(rec.median_us),
            ]
        )
    return "\n".join(
        [
            "## 4. All methods on simulated ground truth\n",
            f"`scanlines.evaluate.evaluate`: {cfg.n} scenes per sensor preset, seed "
            f"{cfg.seed}, noise {cfg.noise}; every method on the same scans. Rates pooled over "
            "scans; us/scan: median, one sample per scan. "
            f"{sim_tolerance_caption(cfg.tol)}.\n",
            _table(
                ["sensor", "method", "bp F1", "corner F1", "TruePos", "FalsePos", "us/scan"],
                rows,
                left=2,
            ),
            f"![ground-truth scores by sensor and method](figures/{figures['bars']})\n",
        ]
    )


def render_markdown(result: ReproduceResult, figures: dict[str, str] | None = None) -> str:
    """``RESULTS.md`` for ``result``; ``figures``: key -> file name in ``figures/``."""
    figures = dict(FIGURES) if figures is None else figures
    cfg = result.config
    tol = cfg.tol
    lab_text = label_tolerance_caption(tol)
    sim_text = sim_tolerance_caption(tol) + "."
    labelled, t1, t3 = result.labelled, result.sim_table1, result.sim_table3
    settings = (
        f"{len(labelled.cases)} labelled Intel frames, {len(t1.cases)} simulated scenes for "
        f"Tables 1 and 3, {len(result.real[0].cases)} scans of each real excerpt, "
        f"{result.ground_truth.config.n} scenes per sensor for section 4, "
        f"{cfg.repeats} timed repeat{'s' if cfg.repeats != 1 else ''}, seed {cfg.seed}"
        + (" (**--quick run**)" if cfg.quick else "")
    )
    parts = [
        "# Results: the paper's experiments, reproduced\n",
        f"<!-- Generated by `{result.command}`. Do not edit: rerun the command. -->\n",
        f"> **Generated** by `{result.command}` (`scanlines.reproduce`) on "
        f"{result.started[:10]} in {result.elapsed_s:.0f} s; never edited by hand: rerun the "
        "command to update. Data: only what the repository ships (the Intel and Freiburg "
        "excerpts of `scanlines.data`, the hand labels `scanlines/data/intel_labels.json`, "
        f"and the scan simulator). Settings: {settings}.\n",
        f"Methods: {', '.join(f'`{s.label}`' for s in result.specs)}, default parameters "
        "(`adaptive:paper` is the paper's text taken literally; `adaptive` is the project's "
        'default reading, see the README). Paper: "An Adaptive Threshold Line Segment '
        'Feature Extraction Algorithm for Laser Radar Scanning Environments", Electronics '
        "11(11), 1759, 2022.\n",
        _machine_line(result) + "\n",
        f"**Tolerances, hand labels:** {lab_text}\n",
        f"**Tolerances, simulated scans:** {sim_text.removeprefix('tolerances: ')}\n",
        _headline_section(result),
        "## 1. Table 1 analogue: breakpoints and corners of 10 Intel frames\n",
        "The paper's Table 1 lists, for 10 Intel frames, the actual (hand-counted) and "
        "extracted numbers of breakpoints and corners of its method only, without saying "
        "which frames or where the events are. Here: the same counts for every method, and "
        "the matched precision and recall that counts alone cannot show.\n",
        f"### 1a. Hand-labelled Intel frames ({len(labelled.cases)})\n",
        f"{labelled.title}. Frames: scans "
        f"{', '.join(str(c.labels.scan) for c in labelled.cases if c.labels is not None)} of "
        "the excerpt; uncertain labels (events a careful reader could not decide) are listed "
        "separately.\n",
        *_label_details(result),
        _table1(labelled, lab_text, "uncertain"),
        f"### 1b. Simulated Intel-like scans ({len(t1.cases)}, lms_1deg)\n",
        f"{t1.title}; actual = every true event of the simulator; don't care = true events "
        "next to runs of fewer than "
        f"{tol.min_run} returns (matching one neither helps nor hurts).\n",
        _table1(t1, sim_text, "don't care"),
        "## 2. Table 3 analogue: counts, accuracy rate, matched scores and time\n",
        "The paper's Table 3 gives, for 10 TiM571 scans, the actual and found counts of IEPF "
        "and its method, the count-based accuracy rate and the time per scan.\n",
        f"### 2a. Simulated TiM571 scans ({len(t3.cases)}, the paper's sensor)\n",
        _table3_truth(t3, sim_text),
        "In the paper's layout (adaptive against IEPF per scan; ms: median over the repeats):\n",
        _table3_paper_layout(t3),
        f"### 2b. Hand-labelled Intel frames ({len(labelled.cases)})\n",
        _table3_truth(labelled, lab_text),
        "### 2c. Real excerpts without labels\n",
        "No truth: counts per scan, the similarity error (mean and RMS point-to-line "
        "distance over all points on segments) with the share of valid returns on segments, "
        "and time.\n",
    ]
    for run_ in result.real:
        parts += [f"**{run_.name}**: {len(run_.cases)} scans, {run_.title}.\n", _table3_real(run_)]
        note = _nonfinite_note(run_)
        if note:
            parts.append(note)
    parts += [_fig13_section(result, figures), _ground_truth_section(result, figures)]
    return "\n".join(parts)


def _label_details(result: ReproduceResult) -> list[str]:
    out = []
    if result.label_how_chosen:
        out.append(f"How the frames were chosen (from the label file): {result.label_how_chosen}\n")
    if result.label_rule:
        out.append(
            "<details><summary>The labelling rule (from the label file)</summary>\n\n"
            f"{result.label_rule}\n\n</details>\n"
        )
    return out


def reproduce(
    out: str | Path = "docs",
    config: ReproduceConfig | None = None,
    *,
    labels: Sequence[LabelledFrameLike] | None = None,
    command: str = "scanlines reproduce",
    on_stage: Stage | None = None,
) -> tuple[ReproduceResult, list[Path]]:
    """:func:`run`, then write ``<out>/RESULTS.md`` and ``<out>/figures/*.png``.

    Returns the result and the written paths (markdown first).
    """
    result = run(config, labels=labels, command=command, on_stage=on_stage)
    if on_stage is not None:
        on_stage("figures and RESULTS.md")
    out = Path(out)
    figures = write_figures(result, out / "figures")
    names = {key: path.name for key, path in figures.items()}
    md = write_text_atomically(out / "RESULTS.md", render_markdown(result, names))
    return result, [md, *figures.values()]
