"""One scan with whatever truth it has, and the score of one method on it.

A :class:`Case` is a scan with simulator truth, with hand labels (the Intel frames of
:mod:`scanlines.data.labels`), or with neither (the rest of the real excerpts).
:func:`score_case` scores an extraction of it against what there is:

* simulator truth: :func:`scanlines.evaluation.metrics.score` with its don't-care rules;
* hand labels: :func:`score_labelled`: found events matched one-to-one to labelled ones
  within ``Tolerances.event_beams`` beams, nearest pairs first; uncertain labels are
  don't care (a detection matched to one is neither a true nor a false positive, and
  missing one is not a false negative);
* always: the environmental-similarity error over the segments with a finite line
  (:func:`line_similarity`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.metrics import accuracy_rate, score, score_events
from scanlines.evaluation.scores import EventScore, SimilarityScore, Tolerances
from scanlines.extraction import ALPHA, RHO
from scanlines.truth import Truth

__all__ = [
    "Case",
    "FrameScore",
    "LabelledFrameLike",
    "label_tolerance_caption",
    "line_similarity",
    "point_distances",
    "score_case",
    "score_labelled",
]


class LabelledFrameLike(Protocol):
    """What scoring needs of a hand-labelled frame (``scanlines.data.labels.LabelledFrame``)."""

    scan: int
    breakpoints: tuple[int, ...]
    corners: tuple[int, ...]
    uncertain_breakpoints: tuple[int, ...]
    uncertain_corners: tuple[int, ...]


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
    (:func:`scanlines.evaluation.metrics.match_events`). A found event matched to a certain label is
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

    The points are those :func:`scanlines.evaluation.metrics.environmental_similarity` counts: the
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

    Returns the :class:`~scanlines.evaluation.scores.SimilarityScore` of those segments (equal to
    :func:`scanlines.evaluation.metrics.environmental_similarity` when every line is finite), the
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
