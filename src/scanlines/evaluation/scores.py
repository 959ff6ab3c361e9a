"""The records of a score: tolerances, and the counts and rates they give.

:mod:`scanlines.evaluation.metrics` computes these records (its docstring states the
rules); this module holds what they are: the :class:`Tolerances` a score is computed
with, the per-kind scores of one scan (:class:`EventScore`, :class:`SegmentScore`,
:class:`SimilarityScore`), all of them together (:class:`ScanScore`) and their pool
over scans (:class:`Summary`). Scores add up (``a + b``) by summing counts and sums, so
pooled rates are micro-averages; every record turns into a flat dict with
``to_dict()`` for CSV or JSON.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = [
    "EventScore",
    "ScanScore",
    "SegmentScore",
    "SimilarityScore",
    "Summary",
    "Tolerances",
    "ratio_or_nan",
]


@dataclass(frozen=True)
class Tolerances:
    """Matching tolerances and don't-care thresholds.

    Parameters
    ----------
    event_beams:
        Largest beam-index distance between a found and a true breakpoint or corner
        that still matches.
    rho:
        Largest ``|d rho|`` in metres for a segment match (Nguyen et al. 2005 use
        thresholds of this order).
    alpha:
        Largest ``|d alpha|`` in radians for a segment match (4 deg).
    overlap:
        Smallest beam-index overlap of a segment match, as a fraction of each segment's
        span; also the share of a segment that must lie inside another to count
        towards split and merge errors.
    min_segment_beams:
        Segments (true or found) spanning fewer beams are don't care.
    min_run:
        True events with fewer true returns than this on either side are don't care.
    curved_dont_care:
        Unmatched found events and segments on curved surfaces are not false.
    truth_dont_care:
        True events the truth itself marks as don't care
        (:attr:`scanlines.truth.Truth.breakpoint_dont_care` and ``corner_dont_care``:
        junctions of touching surfaces, depth steps and turns the range noise hides)
        are don't care. Off by default, so that the presets' figures stay as they
        were; ``scanlines eval family`` turns it on.
    """

    event_beams: int = 2
    rho: float = 0.05
    alpha: float = math.radians(4.0)
    overlap: float = 0.5
    min_segment_beams: int = 8
    min_run: int = 3
    curved_dont_care: bool = True
    truth_dont_care: bool = False

    def __post_init__(self) -> None:
        if self.event_beams < 0 or self.min_segment_beams < 0 or self.min_run < 0:
            raise ValueError("event_beams, min_segment_beams and min_run must be >= 0")
        if not (self.rho >= 0 and self.alpha >= 0 and 0 < self.overlap <= 1):
            raise ValueError("need rho >= 0, alpha >= 0 and 0 < overlap <= 1")

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of the tolerances."""
        return asdict(self)


def ratio_or_nan(num: float, den: float) -> float:
    """``num / den``; NaN when ``den`` is 0."""
    return num / den if den else math.nan


@dataclass(frozen=True)
class EventScore:
    """Matching result for one kind of event (breakpoints or corners).

    Attributes
    ----------
    tp, fp, fn:
        True positives, false positives, false negatives (don't-care excluded).
    n_true, n_found:
        All true and found events, don't care included.
    true_dont_care:
        True events that are don't care.
    found_ignored:
        Found events that are neither true nor false positives.
    offset_sum:
        Sum of ``|found - true|`` beam distances over the true positives.
    """

    tp: int = 0
    fp: int = 0
    fn: int = 0
    n_true: int = 0
    n_found: int = 0
    true_dont_care: int = 0
    found_ignored: int = 0
    offset_sum: float = 0.0

    @property
    def precision(self) -> float:
        """``tp / (tp + fp)``; NaN when nothing counted was found."""
        return ratio_or_nan(self.tp, self.tp + self.fp)

    @property
    def recall(self) -> float:
        """``tp / (tp + fn)``; NaN when there is nothing counted to find."""
        return ratio_or_nan(self.tp, self.tp + self.fn)

    @property
    def f1(self) -> float:
        """``2 tp / (2 tp + fp + fn)``; NaN when all three are zero."""
        return ratio_or_nan(2 * self.tp, 2 * self.tp + self.fp + self.fn)

    @property
    def mean_offset(self) -> float:
        """Mean beam-index distance of the true positives."""
        return ratio_or_nan(self.offset_sum, self.tp)

    def __add__(self, other: EventScore) -> EventScore:
        return EventScore(*(a + b for a, b in zip(_values(self), _values(other), strict=True)))

    def to_dict(self, prefix: str = "") -> dict[str, Any]:
        """Counts and rates as a flat dict, keys prefixed with ``prefix``."""
        out = asdict(self)
        out |= {
            "precision": self.precision,
            "recall": self.recall,
            "f1": self.f1,
            "mean_offset": self.mean_offset,
        }
        return {prefix + k: v for k, v in out.items()}


def _values(obj: Any) -> tuple[Any, ...]:
    return tuple(getattr(obj, f) for f in obj.__dataclass_fields__)


@dataclass(frozen=True)
class SegmentScore:
    """Segment matching result (Nguyen et al. 2005 style).

    Attributes
    ----------
    n_true, n_found:
        True and found segments that count (``>= min_segment_beams`` beams).
    true_dont_care, found_dont_care:
        Short segments, not counted.
    matched:
        Counted true segments matched one-to-one by a found segment.
    false:
        Counted found segments that match nothing (and are not ignored).
    found_ignored:
        Counted found segments matched to a don't-care true segment, or unmatched on a
        curved surface.
    split:
        Counted true segments of which two or more counted found segments lie inside.
    merge:
        Counted found segments inside which two or more counted true segments lie.
    sum_abs_drho, sum_abs_dalpha, sum_endpoint_error:
        Sums over the matches of counted true segments (metres, radians, metres;
        the endpoint error of a match is the mean of its start and end distances).
    """

    n_true: int = 0
    n_found: int = 0
    true_dont_care: int = 0
    found_dont_care: int = 0
    matched: int = 0
    false: int = 0
    found_ignored: int = 0
    split: int = 0
    merge: int = 0
    sum_abs_drho: float = 0.0
    sum_abs_dalpha: float = 0.0
    sum_endpoint_error: float = 0.0

    @property
    def true_pos(self) -> float:
        """Share of (counted) true segments found: Nguyen's TruePos."""
        return ratio_or_nan(self.matched, self.n_true)

    @property
    def false_pos(self) -> float:
        """Share of (counted, not ignored) found segments matching nothing: FalsePos."""
        return ratio_or_nan(self.false, self.n_found - self.found_ignored)

    @property
    def mean_abs_drho(self) -> float:
        """Mean ``|d rho|`` over matches, metres."""
        return ratio_or_nan(self.sum_abs_drho, self.matched)

    @property
    def mean_abs_dalpha(self) -> float:
        """Mean ``|d alpha|`` over matches, radians."""
        return ratio_or_nan(self.sum_abs_dalpha, self.matched)

    @property
    def mean_endpoint_error(self) -> float:
        """Mean distance between true and found endpoints over matches, metres."""
        return ratio_or_nan(self.sum_endpoint_error, self.matched)

    def __add__(self, other: SegmentScore) -> SegmentScore:
        return SegmentScore(*(a + b for a, b in zip(_values(self), _values(other), strict=True)))

    def to_dict(self, prefix: str = "") -> dict[str, Any]:
        """Counts, sums and rates as a flat dict."""
        out = asdict(self)
        out |= {
            "true_pos": self.true_pos,
            "false_pos": self.false_pos,
            "mean_abs_drho": self.mean_abs_drho,
            "mean_abs_dalpha": self.mean_abs_dalpha,
            "mean_abs_dalpha_deg": math.degrees(self.mean_abs_dalpha),
            "mean_endpoint_error": self.mean_endpoint_error,
        }
        return {prefix + k: v for k, v in out.items()}


@dataclass(frozen=True)
class SimilarityScore:
    """The paper's environmental similarity error: point-to-line distances.

    Attributes
    ----------
    n_points:
        Points assigned to segments.
    sum_distance, sum_sq_distance:
        Sums of the perpendicular distances and of their squares.
    max_distance:
        Largest distance (0 with no points).
    """

    n_points: int = 0
    sum_distance: float = 0.0
    sum_sq_distance: float = 0.0
    max_distance: float = 0.0

    @property
    def mean(self) -> float:
        """Mean perpendicular distance, metres."""
        return ratio_or_nan(self.sum_distance, self.n_points)

    @property
    def rms(self) -> float:
        """Root-mean-square perpendicular distance, metres."""
        return math.sqrt(ratio_or_nan(self.sum_sq_distance, self.n_points))

    def __add__(self, other: SimilarityScore) -> SimilarityScore:
        return SimilarityScore(
            self.n_points + other.n_points,
            self.sum_distance + other.sum_distance,
            self.sum_sq_distance + other.sum_sq_distance,
            max(self.max_distance, other.max_distance),
        )

    def to_dict(self, prefix: str = "") -> dict[str, Any]:
        """Sums, mean and RMS as a flat dict."""
        out = asdict(self) | {"mean": self.mean, "rms": self.rms}
        return {prefix + k: v for k, v in out.items()}


@dataclass(frozen=True)
class ScanScore:
    """All measures for one scan, with the tolerances used."""

    breakpoints: EventScore
    corners: EventScore
    segments: SegmentScore
    similarity: SimilarityScore
    accuracy_rate: float
    tolerances: Tolerances = field(default_factory=Tolerances)

    def to_dict(self) -> dict[str, Any]:
        """One flat dict (a CSV row): ``bp_*``, ``corner_*``, ``seg_*``, ``sim_*``, ``tol_*``."""
        return (
            self.breakpoints.to_dict("bp_")
            | self.corners.to_dict("corner_")
            | self.segments.to_dict("seg_")
            | self.similarity.to_dict("sim_")
            | {"accuracy_rate": self.accuracy_rate}
            | {f"tol_{k}": v for k, v in self.tolerances.to_dict().items()}
        )


@dataclass(frozen=True)
class Summary:
    """Scores pooled over scans (micro-averaged: counts and sums added, then rates).

    Attributes
    ----------
    n_scans:
        Scans pooled.
    breakpoints, corners, segments, similarity:
        Summed counts; their rate properties are the micro-averages.
    accuracy_rate_mean:
        Mean of the per-scan accuracy rates (scans without truth events skipped).
    accuracy_rate_pooled:
        The accuracy rate formula on the summed absolute count differences and summed
        true counts.
    tolerances:
        The tolerances all the scores were computed with.
    """

    n_scans: int
    breakpoints: EventScore
    corners: EventScore
    segments: SegmentScore
    similarity: SimilarityScore
    accuracy_rate_mean: float
    accuracy_rate_pooled: float
    tolerances: Tolerances

    def to_dict(self) -> dict[str, Any]:
        """One flat dict, keys as in :meth:`ScanScore.to_dict`."""
        return (
            {"n_scans": self.n_scans}
            | self.breakpoints.to_dict("bp_")
            | self.corners.to_dict("corner_")
            | self.segments.to_dict("seg_")
            | self.similarity.to_dict("sim_")
            | {
                "accuracy_rate_mean": self.accuracy_rate_mean,
                "accuracy_rate_pooled": self.accuracy_rate_pooled,
            }
            | {f"tol_{k}": v for k, v in self.tolerances.to_dict().items()}
        )
