"""Scoring an extraction against exact ground truth.

Three families of measures, all computed per scan by :func:`score` and pooled over
scans by :func:`aggregate`:

* **Events** (breakpoints, corners): one-to-one matching of found to true beam indices
  within ``Tolerances.event_beams`` (greedy by index distance, nearest pairs first;
  circular distance in full-circle scans), giving precision, recall and F1.
  Breakpoints are matched to breakpoints and corners to corners.
* **Segments**, in the style of Nguyen et al. (2005): a found and a true segment
  match when ``|d rho| <= Tolerances.rho``, ``|d alpha| <= Tolerances.alpha`` (angles
  wrapped) and their beam-index overlap is at least ``Tolerances.overlap`` of both
  segments. Matching is one-to-one, best pairs first. ``TruePos`` is the share of true
  segments matched, ``FalsePos`` the share of found segments that match nothing;
  split errors count true segments covered by several found ones, merge errors found
  segments covering several true ones; ``|d rho|``, ``|d alpha|`` and the endpoint
  error are averaged over the matches.
* The paper's measures: the **environmental similarity** error (perpendicular
  distance of every point of a segment to its line, mean and RMS) and the
  count-based **accuracy rate** of its Table 3,
  ``1 - (|bp_found - bp_true| + |c_found - c_true|) / (bp_true + c_true)``.

Don't-care rules (all parameters of :class:`~scanlines.evaluation.scores.Tolerances`):

* segments shorter than ``min_segment_beams`` beams (index span) are don't care, true
  or found: a short true segment is never missed, a short found segment is never
  false, and a found segment matched to a short true one is neither right nor wrong;
  split and merge errors count long segments only;
* a true event with fewer than ``min_run`` true returns on either side (one-beam
  faces, one-point clusters) is don't care: a found event matched to it is neither a
  true nor a false positive, and missing it is not a false negative;
* with ``curved_dont_care``, found events and segments on curved surfaces (round
  pillars, which have no true corners or segments) that match nothing are not false.
* with ``truth_dont_care``, the true events the truth marks as don't care
  (:attr:`~scanlines.truth.Truth.breakpoint_dont_care`, ``corner_dont_care``: junctions
  of touching surfaces, depth steps and turns the range noise hides) are don't care
  like the events next to short runs, the way uncertain hand labels are.

Every result carries the :class:`~scanlines.evaluation.scores.Tolerances` it was
computed with, and turns into a flat dict with ``to_dict()`` for CSV or JSON; the records
are in :mod:`scanlines.evaluation.scores`. The truth is the simulator's, read through its
types only (:mod:`scanlines.truth`).

References
----------
V. Nguyen, A. Martinelli, N. Tomatis, R. Siegwart, "A comparison of line extraction
algorithms using 2D laser rangefinder for indoor mobile robotics", IROS 2005.

G. A. Borges, M.-J. Aldon, "Line extraction in 2D range images for mobile robotics",
Journal of Intelligent and Robotic Systems 40 (2004) 267-297.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.scores import (
    EventScore,
    ScanScore,
    SegmentScore,
    SimilarityScore,
    Summary,
    Tolerances,
    ratio_or_nan,
)
from scanlines.extraction import ALPHA, END_X, END_Y, RHO, START_X, START_Y
from scanlines.truth import Truth

__all__ = [
    "accuracy_rate",
    "aggregate",
    "environmental_similarity",
    "event_dont_care",
    "index_distance",
    "line_differences",
    "match_events",
    "match_one_to_one",
    "score",
    "score_events",
    "score_segments",
    "segment_overlap",
    "wrap_angle",
]


# --------------------------------------------------------------------------- events


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to ``(-pi, pi]``."""
    a = np.asarray(angle, dtype=np.float64)
    wrapped = np.mod(a + math.pi, 2.0 * math.pi) - math.pi
    return np.where(wrapped == -math.pi, math.pi, wrapped)


def index_distance(
    a: np.ndarray, b: np.ndarray, n_beams: int, *, circular: bool = False
) -> np.ndarray:
    """``len(a) x len(b)`` beam-index distances; around the circle when ``circular``."""
    d = np.abs(np.asarray(a, np.intp)[:, None] - np.asarray(b, np.intp)[None, :])
    return np.minimum(d, n_beams - d) if circular else d


def match_events(
    found: np.ndarray,
    true: np.ndarray,
    tolerance: int,
    *,
    n_beams: int,
    circular: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one matching of found to true beam indices within ``tolerance``.

    Greedy by distance: the closest pair is matched first (ties: lower true, then
    lower found position), then the closest of the rest, and so on.

    Returns
    -------
    found_pos, true_pos:
        Positions (into ``found`` and ``true``) of the matched pairs.
    """
    d = index_distance(found, true, n_beams, circular=circular)
    return match_one_to_one(d <= tolerance, d.astype(np.float64))


def match_one_to_one(candidate: np.ndarray, cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one matching over candidate ``(row, column)`` pairs, lowest cost first.

    Ties are broken by the lower column, then the lower row. The loop runs over
    candidate pairs (a few per event or segment), not over beams.
    """
    rows, cols = np.nonzero(candidate)
    order = np.lexsort((rows, cols, cost[rows, cols]))
    used_rows: set[int] = set()
    used_cols: set[int] = set()
    pairs: list[tuple[int, int]] = []
    for r, c in zip(rows[order].tolist(), cols[order].tolist(), strict=True):
        if r not in used_rows and c not in used_cols:
            used_rows.add(r)
            used_cols.add(c)
            pairs.append((r, c))
    arr = np.array(pairs, dtype=np.intp).reshape(-1, 2)
    return arr[:, 0], arr[:, 1]


def score_events(
    found: np.ndarray,
    true: np.ndarray,
    *,
    tolerance: int,
    n_beams: int,
    circular: bool = False,
    true_dont_care: np.ndarray | None = None,
    found_ignorable: np.ndarray | None = None,
) -> EventScore:
    """Score found against true event indices.

    Parameters
    ----------
    found, true:
        Beam indices.
    tolerance:
        Largest matching beam distance.
    n_beams, circular:
        Scan size, and whether index distance wraps around.
    true_dont_care:
        Mask over ``true``: events whose match or miss does not count.
    found_ignorable:
        Mask over ``found``: events that are not false when they match nothing.
    """
    found = np.asarray(found, dtype=np.intp)
    true = np.asarray(true, dtype=np.intp)
    dc = np.zeros(len(true), bool) if true_dont_care is None else np.asarray(true_dont_care, bool)
    ign = (
        np.zeros(len(found), bool) if found_ignorable is None else np.asarray(found_ignorable, bool)
    )
    fpos, tpos = match_events(found, true, tolerance, n_beams=n_beams, circular=circular)
    counted = ~dc[tpos]
    true_matched = np.zeros(len(true), bool)
    true_matched[tpos] = True
    found_matched = np.zeros(len(found), bool)
    found_matched[fpos] = True
    tp = int(np.count_nonzero(counted))
    offsets = np.abs(found[fpos[counted]] - true[tpos[counted]])
    if circular:
        offsets = np.minimum(offsets, n_beams - offsets)
    return EventScore(
        tp=tp,
        fp=int(np.count_nonzero(~found_matched & ~ign)),
        fn=int(np.count_nonzero(~true_matched & ~dc)),
        n_true=len(true),
        n_found=len(found),
        true_dont_care=int(np.count_nonzero(dc)),
        found_ignored=len(found) - tp - int(np.count_nonzero(~found_matched & ~ign)),
        offset_sum=float(offsets.sum()),
    )


# --------------------------------------------------------------------------- segments


def _spans(first: np.ndarray, last: np.ndarray, n_beams: int) -> np.ndarray:
    return (np.asarray(last, np.intp) - np.asarray(first, np.intp)) % n_beams + 1


def _pieces(first: np.ndarray, last: np.ndarray, n_beams: int) -> tuple[np.ndarray, np.ndarray]:
    """Each segment as two inclusive index intervals ``lo[:, k]..hi[:, k]`` (one may be empty)."""
    f, la = np.asarray(first, np.intp), np.asarray(last, np.intp)
    wraps = f > la
    lo = np.stack((f, np.where(wraps, 0, 1)))
    hi = np.stack((np.where(wraps, n_beams - 1, la), np.where(wraps, la, 0)))
    return lo, hi


def segment_overlap(
    first_a: np.ndarray,
    last_a: np.ndarray,
    first_b: np.ndarray,
    last_b: np.ndarray,
    n_beams: int,
) -> np.ndarray:
    """``len(a) x len(b)`` number of beam indices two segments share.

    A segment with ``first > last`` runs across the seam (``first..n-1, 0..last``).
    """
    lo_a, hi_a = _pieces(first_a, last_a, n_beams)
    lo_b, hi_b = _pieces(first_b, last_b, n_beams)
    total = np.zeros((lo_a.shape[1], lo_b.shape[1]), dtype=np.intp)
    for p in range(2):
        for q in range(2):
            lo = np.maximum(lo_a[p][:, None], lo_b[q][None, :])
            hi = np.minimum(hi_a[p][:, None], hi_b[q][None, :])
            total += np.clip(hi - lo + 1, 0, None)
    return total


def line_differences(
    rho_f: np.ndarray, alpha_f: np.ndarray, rho_t: np.ndarray, alpha_t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``|d rho|`` and ``|d alpha|`` of every found/true pair (``len(f) x len(t)``).

    The Hesse form is ambiguous for lines through the origin (``(rho, alpha)`` and
    ``(-rho, alpha + pi)`` are one line); the representation with the smaller angle
    difference is used.
    """
    da = wrap_angle(alpha_f[:, None] - alpha_t[None, :])
    da_flip = wrap_angle(alpha_f[:, None] - alpha_t[None, :] + math.pi)
    flip = np.abs(da_flip) < np.abs(da)
    drho = np.where(flip, rho_f[:, None] + rho_t[None, :], rho_f[:, None] - rho_t[None, :])
    return np.abs(drho), np.abs(np.where(flip, da_flip, da))


def _segment_beams(
    first: np.ndarray, last: np.ndarray, n_beams: int
) -> tuple[np.ndarray, np.ndarray]:
    """All beam indices of all segments (across the seam where ``first > last``).

    Returns the beams and, for each, the index of its segment.
    """
    spans = _spans(first, last, n_beams)
    offsets = np.arange(int(spans.sum())) - np.repeat(np.cumsum(spans) - spans, spans)
    beams = (np.repeat(np.asarray(first, np.intp), spans) + offsets) % n_beams
    return beams, np.repeat(np.arange(len(spans)), spans)


def _on_curve(first: np.ndarray, last: np.ndarray, truth: Truth) -> np.ndarray:
    """Found segments whose beams mostly hit curved surfaces."""
    beams, seg = _segment_beams(first, last, truth.n_beams)
    curved = np.bincount(seg, weights=truth.on_curve[beams], minlength=len(first))
    return curved * 2 > _spans(first, last, truth.n_beams)


def score_segments(extraction: Extraction, truth: Truth, tol: Tolerances) -> SegmentScore:
    """Match found to true segments and count splits and merges (see the module docstring)."""
    n = truth.n_beams
    ts = truth.segments
    f_first, f_last = extraction.first, extraction.last
    f_span, t_span = _spans(f_first, f_last, n), _spans(ts.first, ts.last, n)
    f_long, t_long = f_span >= tol.min_segment_beams, t_span >= tol.min_segment_beams
    shared = segment_overlap(f_first, f_last, ts.first, ts.last, n)
    drho, dalpha = line_differences(
        extraction.lines[:, RHO], extraction.lines[:, ALPHA], ts.rho, ts.alpha
    )
    overlapping = (shared >= tol.overlap * f_span[:, None]) & (
        shared >= tol.overlap * t_span[None, :]
    )
    candidate = overlapping & (drho <= tol.rho) & (dalpha <= tol.alpha)
    cost = drho / max(tol.rho, 1e-12) + dalpha / max(tol.alpha, 1e-12)
    fpos, tpos = match_one_to_one(candidate, cost)

    counted = t_long[tpos]
    f_c, t_c = fpos[counted], tpos[counted]
    found_start = extraction.lines[f_c][:, [START_X, START_Y]]
    found_end = extraction.lines[f_c][:, [END_X, END_Y]]
    endpoint = (
        np.hypot(*(found_start - ts.start[t_c]).T) + np.hypot(*(found_end - ts.end[t_c]).T)
    ) / 2

    f_matched = np.zeros(len(f_first), bool)
    f_matched[fpos] = True
    f_to_dc_true = np.zeros(len(f_first), bool)
    f_to_dc_true[fpos[~counted]] = True
    unmatched = f_long & ~f_matched
    if tol.curved_dont_care:
        ignorable = unmatched & _on_curve(f_first, f_last, truth)
    else:
        ignorable = np.zeros(len(f_first), bool)

    inside_true = (shared >= tol.overlap * f_span[:, None]) & f_long[:, None] & t_long[None, :]
    inside_found = (shared >= tol.overlap * t_span[None, :]) & f_long[:, None] & t_long[None, :]
    return SegmentScore(
        n_true=int(np.count_nonzero(t_long)),
        n_found=int(np.count_nonzero(f_long)),
        true_dont_care=int(np.count_nonzero(~t_long)),
        found_dont_care=int(np.count_nonzero(~f_long)),
        matched=len(t_c),
        false=int(np.count_nonzero(unmatched & ~ignorable)),
        found_ignored=int(np.count_nonzero((f_long & f_to_dc_true) | ignorable)),
        split=int(np.count_nonzero(inside_true.sum(axis=0) >= 2)),
        merge=int(np.count_nonzero(inside_found.sum(axis=1) >= 2)),
        sum_abs_drho=float(drho[f_c, t_c].sum()),
        sum_abs_dalpha=float(dalpha[f_c, t_c].sum()),
        sum_endpoint_error=float(endpoint.sum()),
    )


# --------------------------------------------------------------------------- paper measures


def environmental_similarity(extraction: Extraction, scan: Scan) -> SimilarityScore:
    """Perpendicular distance of each point to its segment's line (the paper's Fig. 13).

    The points of a segment are the valid beams in ``first..last`` (across the seam
    when ``first > last``) that are not in ``extraction.outliers``. Segments without
    a finite line (the paper's fit on a run with no slope) are left out.
    """
    beams, seg = _segment_beams(extraction.first, extraction.last, len(scan))
    keep = scan.valid[beams] & ~np.isin(beams, extraction.outliers)
    beams, seg = beams[keep], seg[keep]
    pts = scan.points[beams]
    rho, alpha = extraction.lines[seg, RHO], extraction.lines[seg, ALPHA]
    with np.errstate(invalid="ignore"):
        d = np.abs(pts[:, 0] * np.cos(alpha) + pts[:, 1] * np.sin(alpha) - rho)
    d = d[np.isfinite(d)]
    return SimilarityScore(
        n_points=len(d),
        sum_distance=float(d.sum()),
        sum_sq_distance=float((d * d).sum()),
        max_distance=float(d.max()) if len(d) else 0.0,
    )


def accuracy_rate(bp_found: int, bp_true: int, c_found: int, c_true: int) -> float:
    """The paper's count-based accuracy rate (Table 3); NaN when there is no truth.

    ``1 - (|bp_found - bp_true| + |c_found - c_true|) / (bp_true + c_true)``. It only
    compares counts, so a detection in the wrong place is not seen; it can be negative.
    """
    return 1.0 - ratio_or_nan(abs(bp_found - bp_true) + abs(c_found - c_true), bp_true + c_true)


# --------------------------------------------------------------------------- per scan, pooled


def event_dont_care(runs: np.ndarray, min_run: int) -> np.ndarray:
    """Events (``K x 2`` run lengths before and after) next to a run shorter than ``min_run``."""
    return np.asarray(runs).reshape(-1, 2).min(axis=1, initial=np.iinfo(np.intp).max) < min_run


def _check_indices(name: str, values: np.ndarray, n: int) -> None:
    if len(values) and (values.min() < 0 or values.max() >= n):
        raise ValueError(f"extraction.{name} has beam indices outside 0..{n - 1}")


def score(
    extraction: Extraction, truth: Truth, scan: Scan, tol: Tolerances | None = None
) -> ScanScore:
    """Score one extraction against the ground truth of its scan.

    Parameters
    ----------
    extraction:
        What an extractor found in ``scan``.
    truth:
        The exact truth (:attr:`scanlines.sim.SimScan.truth`).
    scan:
        The scan (for the environmental similarity).
    tol:
        Tolerances; :class:`Tolerances` defaults when ``None``.

    Returns
    -------
    ScanScore

    Raises
    ------
    ValueError
        When scan, truth and extraction disagree on the number of beams.
    """
    tol = Tolerances() if tol is None else tol
    n = truth.n_beams
    if len(scan) != n:
        raise ValueError(f"scan has {len(scan)} beams but the truth has {n}")
    for name in ("first", "last", "breakpoints", "corners", "outliers"):
        _check_indices(name, getattr(extraction, name), n)
    circular = truth.full_circle

    def ignorable(found: np.ndarray) -> np.ndarray:
        if not tol.curved_dont_care:
            return np.zeros(len(found), bool)
        return truth.on_curve[found]

    bps = score_events(
        extraction.breakpoints,
        truth.breakpoints,
        tolerance=tol.event_beams,
        n_beams=n,
        circular=circular,
        true_dont_care=event_dont_care(truth.breakpoint_runs, tol.min_run)
        | (tol.truth_dont_care & truth.breakpoint_dont_care),
        found_ignorable=ignorable(extraction.breakpoints),
    )
    corners = score_events(
        extraction.corners,
        truth.corners,
        tolerance=tol.event_beams,
        n_beams=n,
        circular=circular,
        true_dont_care=event_dont_care(truth.corner_runs, tol.min_run)
        | (tol.truth_dont_care & truth.corner_dont_care),
        found_ignorable=ignorable(extraction.corners),
    )
    return ScanScore(
        breakpoints=bps,
        corners=corners,
        segments=score_segments(extraction, truth, tol),
        similarity=environmental_similarity(extraction, scan),
        accuracy_rate=accuracy_rate(
            len(extraction.breakpoints),
            len(truth.breakpoints),
            len(extraction.corners),
            len(truth.corners),
        ),
        tolerances=tol,
    )


def aggregate(scores: Iterable[ScanScore]) -> Summary:
    """Pool per-scan scores into a :class:`Summary`.

    Raises
    ------
    ValueError
        With no scores, or when the scores were computed with different tolerances.
    """
    items: Sequence[ScanScore] = list(scores)
    if not items:
        raise ValueError("aggregate needs at least one ScanScore")
    tol = items[0].tolerances
    if any(s.tolerances != tol for s in items):
        raise ValueError("cannot pool scores computed with different tolerances")
    bps = sum((s.breakpoints for s in items), EventScore())
    corners = sum((s.corners for s in items), EventScore())
    rates = np.array([s.accuracy_rate for s in items], dtype=np.float64)
    diff = sum(
        abs(s.breakpoints.n_found - s.breakpoints.n_true)
        + abs(s.corners.n_found - s.corners.n_true)
        for s in items
    )
    return Summary(
        n_scans=len(items),
        breakpoints=bps,
        corners=corners,
        segments=sum((s.segments for s in items), SegmentScore()),
        similarity=sum((s.similarity for s in items), SimilarityScore()),
        accuracy_rate_mean=float(rates[np.isfinite(rates)].mean())
        if np.isfinite(rates).any()
        else math.nan,
        accuracy_rate_pooled=1.0 - ratio_or_nan(diff, bps.n_true + corners.n_true),
        tolerances=tol,
    )
