"""Steps shared by the comparison methods: cutting, growing and joining runs of points.

A *run* is an inclusive interval ``[a, b]`` of sequence positions (see
:mod:`scanlines.steps.points`); ``group`` numbers the cluster (or the line) each run
came from. Everything here works on many runs at once.

Clustering and assembly
    :func:`cluster_sequence` clusters by the method's ``breakpoints`` rule (or
    not at all, ``"none"``), with the seam of full circles handled as the adaptive
    method does; :func:`finish` drops small runs, finds the events and assembles
    the :class:`~scanlines.Extraction`.
Splitting
    :func:`split_runs` is the recursive split of iterative end-point fit [1]_ [2]_
    (``reference="chord"``: a run is split while a point is farther than the
    threshold from the chord from its first to its last point) and of
    split-and-merge [3]_ (``reference="fit"``: ... from the run's
    total-least-squares line). Either way the cut is at the interior point
    farthest from the chord (see :func:`split_runs`). One pass handles every run
    of one recursion level; the loop is over levels. The split point joins the
    part whose line (fitted without it) it is nearer, so no point is lost.
Runs from inlier masks
    :func:`inlier_runs` turns the consensus set of one line (RANSAC, Hough) into
    runs that are contiguous in beam order: consecutive inliers stay in one run
    when at most ``max_bridge`` returns lie between them (returns not yet taken by
    another segment; they become outliers), no two or more consecutive beams are
    missing between them (the project's gap convention) and they are at most
    ``max_gap`` metres apart. :func:`consensus_segments` is the loop of the
    consensus methods around it (propose a line, refit, cut into runs, remove),
    :func:`consensus_extraction` the whole method given its line search.
Merging
    :func:`merge_chi_square` joins neighbouring runs of one cluster whose lines
    agree within a chi-square bound on ``(rho, alpha)``, with the covariances of
    :func:`~scanlines.steps.fit.line_covariances` and the angle difference wrapped
    to ``(-pi, pi]`` (:func:`line_difference`), as the merge of split-and-merge
    [3]_ [4]_. Greedy: the most similar pair first, refitted, until no pair passes.
Corners and breakpoints between segments (:func:`segment_events`)
    The one rule every comparison method uses. Of two consecutive segments, with
    facing end points ``P_e`` (last of the first) and ``P_s`` (first of the
    second), at most ``corner_beams`` beams apart:

    * they make a **corner** when their lines turn by at least ``corner_angle``
      and the lines' intersection ``X`` is within ``corner_distance`` metres of
      both ``P_e`` and ``P_s``; the corner is reported at the return nearest ``X``
      among those from ``corner_beams`` positions before ``P_e`` to
      ``corner_beams`` after ``P_s`` (a split one or two returns off the true
      corner, as noise makes it, does not move the corner);
    * they **continue** one surface (no event) when they turn by less than
      ``corner_angle`` and each facing end is within ``corner_distance`` of the
      other segment's line: one wall cut in two;
    * otherwise, and always when the facing ends are farther apart in beams, the
      pair is a **jump**.

    A method with its own clustering tests only segments of one cluster and takes
    its breakpoints from the clustering. A method without (RANSAC and Hough on
    the whole scan) reports a **breakpoint** at the last beam of the first
    segment of every jump. In a full-circle scan the last segment is followed by
    the first, across the seam.

    Defaults: ``corner_beams = 2`` tolerates one return between the segments (a
    corner return left to neither side). ``corner_distance = 0.2`` m: the true
    corner lies within one beam spacing of the facing returns, and the spacing is
    ``rho dtheta / cos(incidence)``: 0.17 m for a 1 deg scanner at 5 m and 60 deg
    incidence, the coarsest case of the simulated sensors' typical geometry.
    ``corner_angle = 10`` deg: two total-least-squares fits to halves of one wall
    differ in angle by the fits' noise, about 2 deg (one standard deviation) for
    0.5 m halves with 2 cm range noise at 1/3 deg; a turn of 10 deg is well beyond
    that, while real corners of indoor walls turn by far more.

References
----------
.. [1] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973 (iterative end-point fit).
.. [2] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE Trans.
   Computers C-23(8), 860-870, 1974 (split-and-merge).
.. [3] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of line
   extraction algorithms using 2D laser rangefinder for indoor mobile robotics",
   IEEE/RSJ IROS 2005, 1929-1934.
.. [4] K. O. Arras and R. Siegwart, "Feature extraction and scene interpretation
   for map-based navigation and map building", SPIE Mobile Robotics XII, 1997.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np

from scanlines.extraction import Extraction
from scanlines.params import Param, int_at_least, number
from scanlines.scan import is_full_circle
from scanlines.steps.assemble import assemble
from scanlines.steps.breakpoints import (
    BREAKPOINT_PARAMS,
    MAX_BRIDGED_GAP,
    BreakpointRule,
    Clusters,
    cluster_scan,
)
from scanlines.steps.corners import strongest_turn
from scanlines.steps.denoise import estimate_noise
from scanlines.steps.fit import (
    Lines,
    Moments,
    line_covariances,
    point_residuals,
    run_labels,
    tls_lines,
)
from scanlines.steps.points import Sequence

__all__ = [
    "BRIDGE_RETURNS",
    "EVENT_PARAMS",
    "LITERAL_CLUSTERING",
    "LineFinder",
    "cluster_sequence",
    "consensus_extraction",
    "consensus_segments",
    "drop_small",
    "finish",
    "inlier_runs",
    "line_difference",
    "line_intersections",
    "merge_chi_square",
    "pair_chi_square",
    "remove_positions",
    "segment_events",
    "split_runs",
]

EVENT_PARAMS: dict[str, Param] = {
    "corner_beams": Param(
        2, int_at_least(1), "corner: most beams between the facing ends of two segments"
    ),
    "corner_distance": Param(
        0.2,
        number(low=0.0, low_open=True),
        "corner: largest distance (m) of a facing end from the two lines' intersection",
    ),
    "corner_angle": Param(
        10.0, number(low=0.0, high=90.0), "corner: smallest turn between the two lines (deg)"
    ),
}
"""Parameters of the shared corner/breakpoint rule (:func:`segment_events`)."""

LITERAL_CLUSTERING: dict[str, Param] = {
    name: Param(0.0, BREAKPOINT_PARAMS[name].check, BREAKPOINT_PARAMS[name].doc + "; off here")
    for name in ("line_k",)
}
"""Overrides of :data:`~scanlines.steps.breakpoints.BREAKPOINT_PARAMS`: the published
clustering rules have no line-continuation bridge."""

NO_CLUSTERING = "none"
"""The ``breakpoints`` value of a method that works on the whole scan."""

_EMPTY = np.zeros(0, dtype=np.intp)

# The ring anchor (a full circle without any gap) is the strongest turn-angle corner.
_RING_WINDOW = 5


def _ring_anchor(seq: Sequence) -> int:
    return strongest_turn(seq, _RING_WINDOW)


# --------------------------------------------------------------------------- clustering


def cluster_sequence(seq: Sequence, params: Mapping[str, Any]) -> tuple[Sequence, Clusters, bool]:
    """Cluster ``seq`` by the method's ``breakpoints`` rule, joining the seam of full circles.

    ``breakpoints="none"`` (methods that work on the whole scan) returns one
    cluster over every return; a full circle is still rotated to start after a gap
    of missing beams (or, without any, at its strongest corner), so that no run
    needs to cross the end of the sequence.

    Returns the (possibly rotated) sequence, its clusters and whether the scan is
    one closed ring (a full circle without any break).
    """
    name = params["breakpoints"]
    if name == NO_CLUSTERING:
        rule = BreakpointRule(name="fixed", jump_distance=math.inf)
        seq, _, ring = cluster_scan(seq, rule, _ring_anchor)
        whole = Clusters(np.array([0], dtype=np.intp), np.array([len(seq) - 1]), _EMPTY)
        return seq, whole, ring
    sigma = 0.0
    noisy_rule = name in ("adaptive", "abd") and params.get("noise_k", 0.0) > 0.0
    if noisy_rule or params.get("line_k", 0.0) > 0.0:
        sigma = estimate_noise(seq, np.array([0]), np.array([len(seq) - 1]))
    rule = BreakpointRule.from_params(dict(params), sigma)
    return cluster_scan(seq, rule, _ring_anchor)


# --------------------------------------------------------------------------- distances


def chord_distances(
    x: np.ndarray,
    y: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    position: np.ndarray,
    run: np.ndarray,
) -> np.ndarray:
    """Distance of each labelled point to the chord from its run's first to last point.

    The chord is the segment between the two points: a point whose foot lies
    beyond an end is measured to that end. For a cluster that nearly closes on
    itself (a room seen all round) the chord is short and its line points
    anywhere; measured to the segment, the farthest point is the far corner,
    not an arbitrary point of the side opposite the chord.
    """
    ax, ay = x[a][run], y[a][run]
    dx, dy = (x[b] - x[a])[run], (y[b] - y[a])[run]
    px, py = x[position] - ax, y[position] - ay
    length2 = dx * dx + dy * dy
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip((px * dx + py * dy) / length2, 0.0, 1.0)
    t = np.where(length2 > 0.0, t, 0.0)
    return np.hypot(px - t * dx, py - t * dy)


def line_distances(
    x: np.ndarray, y: np.ndarray, lines: Lines, position: np.ndarray, run: np.ndarray
) -> np.ndarray:
    """Orthogonal distance of each labelled point to its run's line."""
    return np.abs(point_residuals(x, y, lines.rho, lines.alpha, position, run))


def _farthest(
    distance: np.ndarray, run: np.ndarray, lengths: np.ndarray, position: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Largest ``distance`` of each run and the first position where it occurs."""
    offsets = np.cumsum(lengths) - lengths
    worst = np.maximum.reduceat(distance, offsets)
    hit = np.flatnonzero(distance == worst[run])
    _, first = np.unique(run[hit], return_index=True)
    return worst, position[hit[first]]


# --------------------------------------------------------------------------- splitting


def split_runs(
    seq: Sequence,
    moments: Moments,
    a: np.ndarray,
    b: np.ndarray,
    group: np.ndarray,
    *,
    threshold: float,
    reference: str = "chord",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split runs recursively at the point farthest from their chord while needed.

    A run is split while one of its interior points is farther than
    ``threshold`` from its ``reference``: the chord (iterative end-point fit) or
    its total-least-squares line (split-and-merge). The cut is always at the
    interior point farthest from the chord: on an L-shaped run the fitted line
    is as far from the two ends as from the corner, and cutting where it is
    farthest would split the end points off one by one.

    Parameters
    ----------
    seq, moments:
        The points and their prefix sums.
    a, b, group:
        Runs ``[a, b]`` and their cluster numbers.
    threshold:
        Largest distance (m) a point of a final run may have from its reference.
    reference:
        ``"chord"`` (iterative end-point fit) or ``"fit"`` (the run's TLS line).

    Returns
    -------
    a, b, group:
        The final runs in sequence order. Every point of the input runs is in
        exactly one of them.
    """
    done: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    a, b, group = (np.asarray(v, dtype=np.intp) for v in (a, b, group))
    while a.size:
        splittable = b - a >= 2
        done.append((a[~splittable], b[~splittable], group[~splittable]))
        a, b, group = a[splittable], b[splittable], group[splittable]
        if a.size == 0:
            break
        worst, at = _worst_points(seq, moments, a, b, "chord")
        if reference == "fit":
            worst, _ = _worst_points(seq, moments, a, b, "fit")
        split = worst > threshold
        done.append((a[~split], b[~split], group[~split]))
        a, b, group, at = a[split], b[split], group[split], at[split]
        cut = _side_of_split_point(seq, moments, a, b, at)
        a, b, group = np.r_[a, cut + 1], np.r_[cut, b], np.r_[group, group]
    return _ordered(done)


def _worst_points(
    seq: Sequence, moments: Moments, a: np.ndarray, b: np.ndarray, reference: str
) -> tuple[np.ndarray, np.ndarray]:
    """Farthest interior point of each run (length >= 3) from its chord or line."""
    position, run = run_labels(a, b, len(seq))
    if reference == "chord":
        distance = chord_distances(seq.x, seq.y, a, b, position, run)
    else:
        distance = line_distances(seq.x, seq.y, tls_lines(moments, a, b), position, run)
    end = (position == a[run]) | (position == b[run])
    distance = np.where(end | np.isnan(distance), -np.inf, distance)
    return _farthest(distance, run, b - a + 1, position)


def _side_of_split_point(
    seq: Sequence, moments: Moments, a: np.ndarray, b: np.ndarray, at: np.ndarray
) -> np.ndarray:
    """Last position of the first part: ``at`` or ``at - 1``.

    The split point joins the part whose TLS line (fitted without it) it is
    nearer; next to an end (one point on that side) it joins that short side, the
    long side being the one it does not fit.
    """
    if a.size == 0:
        return at
    left = tls_lines(moments, a, np.maximum(at - 1, a))
    right = tls_lines(moments, np.minimum(at + 1, b), b)
    index = np.arange(a.size)
    to_left = np.abs(point_residuals(seq.x, seq.y, left.rho, left.alpha, at, index))
    to_right = np.abs(point_residuals(seq.x, seq.y, right.rho, right.alpha, at, index))
    joins_left = ~(to_left > to_right)
    joins_left = np.where(at - a < 2, True, np.where(b - at < 2, False, joins_left))
    return np.where(joins_left, at, at - 1)


def _ordered(
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if not parts:
        return _EMPTY, _EMPTY, _EMPTY
    a = np.concatenate([p[0] for p in parts]).astype(np.intp)
    b = np.concatenate([p[1] for p in parts]).astype(np.intp)
    group = np.concatenate([p[2] for p in parts]).astype(np.intp)
    order = np.argsort(a, kind="stable")
    return a[order], b[order], group[order]


# --------------------------------------------------------------------------- inlier runs


def inlier_runs(
    seq: Sequence,
    inlier: np.ndarray,
    free: np.ndarray,
    *,
    max_bridge: int,
    max_gap: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of a consensus set that are contiguous in beam order.

    Parameters
    ----------
    seq:
        The points.
    inlier:
        Mask over positions: the consensus set of one line.
    free:
        Mask over positions not taken by an earlier segment.
    max_bridge:
        Most returns between two consecutive inliers of one run; they must be free.
    max_gap:
        Largest distance (m) between consecutive inliers of one run.

    Returns
    -------
    a, b:
        Runs (first and last inlier).
    bridged:
        Positions inside the runs that are not inliers (to be dropped as outliers).
    """
    found = np.flatnonzero(inlier)
    if found.size == 0:
        return _EMPTY, _EMPTY, _EMPTY
    before, after = found[:-1], found[1:]
    skipped = after - before - 1
    taken = np.r_[0, np.cumsum(~free)]
    wide = np.r_[0, np.cumsum(seq.gap > MAX_BRIDGED_GAP)]
    distance = np.hypot(seq.x[after] - seq.x[before], seq.y[after] - seq.y[before])
    joined = (
        (skipped <= max_bridge)
        & (taken[after] - taken[before + 1] == 0)
        & (wide[after] - wide[before] == 0)
        & (distance <= max_gap)
    )
    cut = np.flatnonzero(~joined)
    a = found[np.r_[0, cut + 1]]
    b = found[np.r_[cut, found.size - 1]]
    covered = _covered(len(seq), a, b)
    return a.astype(np.intp), b.astype(np.intp), np.flatnonzero(covered & ~inlier)


def remove_positions(
    seq: Sequence, a: np.ndarray, b: np.ndarray, drop: np.ndarray
) -> tuple[Sequence, np.ndarray, np.ndarray]:
    """The sequence without positions ``drop``, and runs ``[a, b]`` renumbered.

    The first and last positions of every run must be kept.
    """
    if drop.size == 0:
        return seq, a, b
    keep = np.ones(len(seq), dtype=bool)
    keep[drop] = False
    new_position = np.cumsum(keep) - 1
    return seq.subset(keep), new_position[a], new_position[b]


BRIDGE_RETURNS = 1
"""Most returns between two consecutive inliers of one consensus run (:func:`inlier_runs`):
one return off the line (a noise peak, a spurious echo) does not cut a wall."""


class LineFinder(Protocol):
    """The search of one consensus method (RANSAC, Hough) for its next line."""

    def best_line(self, free: np.ndarray) -> tuple[float, float] | None:
        """``(rho, alpha)`` of the best line through the ``free`` positions, or ``None``."""
        ...

    def remove(self, positions: np.ndarray) -> None:
        """Forget the points at ``positions`` (they belong to a segment now)."""
        ...


def consensus_segments(
    seq: Sequence,
    member: np.ndarray,
    finder: LineFinder,
    *,
    inlier_distance: float,
    min_points: int,
    max_gap: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments of one set of points found line by line (sequential RANSAC, Hough).

    Repeatedly: the finder proposes a line through the free points of ``member``;
    its inliers (within ``inlier_distance``) are refitted by total least squares
    and collected again; the consensus set is cut into runs contiguous in beam
    order (:func:`inlier_runs`); runs of at least ``min_points`` inliers become
    segments and their points leave the set. When no run is long enough the
    whole consensus set leaves instead, so every round removes points. Stops
    when fewer than ``min_points`` free points remain or a line has fewer
    inliers.

    Returns
    -------
    a, b:
        Segments (unordered).
    bridged:
        Positions inside segments that are off their line (outliers).
    """
    free = member.copy()
    runs_a: list[np.ndarray] = []
    runs_b: list[np.ndarray] = []
    bridged_all: list[np.ndarray] = []
    while np.count_nonzero(free) >= min_points:
        proposal = finder.best_line(free)
        if proposal is None:
            break
        inlier = _refitted_inliers(seq, free, proposal, inlier_distance)
        if np.count_nonzero(inlier) < min_points:
            break
        a, b, bridged = inlier_runs(seq, inlier, free, max_bridge=BRIDGE_RETURNS, max_gap=max_gap)
        long_enough = _run_inlier_counts(inlier, a, b) >= min_points
        taken = _covered(len(seq), a[long_enough], b[long_enough])
        if not long_enough.any():
            taken = inlier
        runs_a.append(a[long_enough])
        runs_b.append(b[long_enough])
        bridged_all.append(bridged[taken[bridged]])
        free &= ~taken
        finder.remove(np.flatnonzero(taken))
    if not runs_a:
        return _EMPTY, _EMPTY, _EMPTY
    return (
        np.concatenate(runs_a).astype(np.intp),
        np.concatenate(runs_b).astype(np.intp),
        np.concatenate(bridged_all).astype(np.intp),
    )


def consensus_extraction(
    seq: Sequence,
    angle_min: float,
    params: Mapping[str, Any],
    *,
    method: str,
    finder: Callable[[Sequence, np.ndarray], LineFinder],
) -> Extraction:
    """A consensus method (RANSAC, Hough) from clustering to the extraction.

    ``finder(seq, member)`` makes the line search for the points ``member`` of
    one cluster (``breakpoints="none"``: one cluster of every point). Clusters
    with fewer than ``min_points`` points are skipped; the returns bridged inside
    segments are dropped as outliers before the segments are fitted.
    """
    seq, clusters, ring = cluster_sequence(seq, params)
    found_a, found_b, found_group, found_bridged = [], [], [], []
    for c, (first, last) in enumerate(zip(clusters.start, clusters.end, strict=True)):
        if last - first + 1 < params["min_points"]:
            continue
        member = np.zeros(len(seq), dtype=bool)
        member[first : last + 1] = True
        a, b, bridged = consensus_segments(
            seq,
            member,
            finder(seq, member),
            inlier_distance=params["inlier_distance"],
            min_points=params["min_points"],
            max_gap=params["max_gap"],
        )
        found_a.append(a)
        found_b.append(b)
        found_group.append(np.full(a.size, c, dtype=np.intp))
        found_bridged.append(bridged)
    a, b, group, bridged = (
        np.concatenate(part).astype(np.intp) if part else _EMPTY
        for part in (found_a, found_b, found_group, found_bridged)
    )
    order = np.argsort(a, kind="stable")
    outliers = seq.index[bridged]
    seq, a, b = remove_positions(seq, a[order], b[order], bridged)
    return finish(
        seq,
        a,
        b,
        group[order],
        clusters=None if params["breakpoints"] == NO_CLUSTERING else clusters,
        ring=ring,
        outliers=outliers,
        angle_min=angle_min,
        method=method,
        params=params,
    )


def _refitted_inliers(
    seq: Sequence, free: np.ndarray, line: tuple[float, float], inlier_distance: float
) -> np.ndarray:
    """Free points near ``line``, collected again around their own TLS line.

    Falls back to the first set when the refitted line keeps fewer points.
    """
    rho, alpha = line
    first = free & (
        np.abs(seq.x * math.cos(alpha) + seq.y * math.sin(alpha) - rho) <= inlier_distance
    )
    chosen = np.flatnonzero(first)
    if chosen.size < 2:
        return first
    fitted = tls_lines(
        Moments(seq.x[chosen], seq.y[chosen]), np.array([0]), np.array([chosen.size - 1])
    )
    off = np.abs(seq.x * np.cos(fitted.alpha[0]) + seq.y * np.sin(fitted.alpha[0]) - fitted.rho[0])
    second = free & (off <= inlier_distance)
    return second if np.count_nonzero(second) >= chosen.size else first


def _run_inlier_counts(inlier: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    total = np.r_[0, np.cumsum(inlier)]
    return total[b + 1] - total[a]


def _covered(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mask of the positions inside runs ``[a, b]``."""
    edge = np.zeros(n + 1, dtype=np.intp)
    np.add.at(edge, a, 1)
    np.add.at(edge, b + 1, -1)
    return np.cumsum(edge[:-1]) > 0


# --------------------------------------------------------------------------- merging


def line_difference(
    rho_1: np.ndarray, alpha_1: np.ndarray, rho_2: np.ndarray, alpha_2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(rho_1 - rho_2, alpha_1 - alpha_2)`` with the angle wrapped to ``(-pi, pi]``.

    Hesse parameters are ambiguous for a line through the origin (``(rho, alpha)``
    and ``(-rho, alpha + pi)``); of the two the one with the smaller angle
    difference is used.
    """
    direct = _wrap(alpha_1 - alpha_2)
    flipped = _wrap(alpha_1 - alpha_2 + np.pi)
    flip = np.abs(flipped) < np.abs(direct)
    return np.where(flip, rho_1 + rho_2, rho_1 - rho_2), np.where(flip, flipped, direct)


def _wrap(angle: np.ndarray) -> np.ndarray:
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def pair_chi_square(
    lines: Lines, covariance: np.ndarray, first: np.ndarray, second: np.ndarray
) -> np.ndarray:
    """``dL^T (P_1 + P_2)^-1 dL`` of line pairs; NaN where the sum is singular."""
    d_rho, d_alpha = line_difference(
        lines.rho[first], lines.alpha[first], lines.rho[second], lines.alpha[second]
    )
    with np.errstate(all="ignore"):  # degenerate runs carry inf/NaN covariances
        total = covariance[first] + covariance[second]
        p, q, s = total[:, 0, 0], total[:, 0, 1], total[:, 1, 1]
        det = p * s - q * q
        value = (s * d_rho * d_rho - 2.0 * q * d_rho * d_alpha + p * d_alpha * d_alpha) / det
    return np.where(det > 0.0, value, np.nan)


def merge_chi_square(
    seq: Sequence,
    moments: Moments,
    a: np.ndarray,
    b: np.ndarray,
    group: np.ndarray,
    *,
    range_sigma: float,
    threshold: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Merge neighbouring runs of one group while their lines pass the chi-square test.

    The pair with the smallest chi-square below ``threshold`` is merged (the
    runs and everything between them), refitted, and the test repeated.
    """
    a, b, group = a.copy(), b.copy(), group.copy()
    while a.size >= 2:
        pair = np.flatnonzero(group[:-1] == group[1:])
        if pair.size == 0:
            break
        lines = tls_lines(moments, a, b)
        position, run = run_labels(a, b, len(seq))
        covariance = line_covariances(
            seq.x, seq.y, seq.r, lines.rho, lines.alpha, position, run, range_sigma
        )
        value = pair_chi_square(lines, covariance, pair, pair + 1)
        value = np.where(np.isnan(value), np.inf, value)
        best = int(np.argmin(value))
        if not value[best] < threshold:
            break
        k = int(pair[best])
        b[k] = b[k + 1]
        a, b, group = np.delete(a, k + 1), np.delete(b, k + 1), np.delete(group, k + 1)
    return a, b, group


# --------------------------------------------------------------------------- events


def line_intersections(
    lines: Lines, first: np.ndarray, second: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Intersection of line pairs (NaN for parallel lines)."""
    ai, aj = lines.alpha[first], lines.alpha[second]
    ri, rj = lines.rho[first], lines.rho[second]
    det = np.sin(aj - ai)
    parallel = ~(np.abs(det) > 1e-12)
    with np.errstate(all="ignore"):
        x = (ri * np.sin(aj) - rj * np.sin(ai)) / det
        y = (rj * np.cos(ai) - ri * np.cos(aj)) / det
    return np.where(parallel, np.nan, x), np.where(parallel, np.nan, y)


def segment_events(
    seq: Sequence,
    moments: Moments,
    a: np.ndarray,
    b: np.ndarray,
    *,
    group: np.ndarray | None,
    wrap: bool,
    corner_beams: int,
    corner_distance: float,
    corner_angle: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Corners and breakpoints between consecutive segments (the module's shared rule).

    Parameters
    ----------
    seq, moments:
        The points and their prefix sums.
    a, b:
        Final segments, in sequence order.
    group:
        Cluster of each segment for a method with clustering: only segments of one
        cluster can meet at a corner, and no breakpoints are derived. ``None`` for
        a method without: every jump between consecutive segments is a breakpoint.
    wrap:
        Whether the last segment is followed by the first (across the seam).
    corner_beams, corner_distance, corner_angle:
        The bounds of the rule (beams, metres, degrees).

    Returns
    -------
    corners, breakpoints:
        Sorted beam indices.
    """
    m = a.size
    if m == 0 or (m == 1 and not wrap):
        return _EMPTY, _EMPTY
    first = np.arange(m - 1) if not (wrap and m >= 2) else np.arange(m)
    second = (first + 1) % m
    if group is not None:
        first = first[group[first] == group[second]]
        second = (first + 1) % m
    end, start = b[first], a[second]
    lines = tls_lines(moments, a, b)
    _, turn = line_difference(
        lines.rho[first], lines.alpha[first], lines.rho[second], lines.alpha[second]
    )
    turns = np.abs(turn) >= math.radians(corner_angle)
    cx, cy = line_intersections(lines, first, second)
    to_end = np.hypot(seq.x[end] - cx, seq.y[end] - cy)
    to_start = np.hypot(seq.x[start] - cx, seq.y[start] - cy)
    near = (seq.index[start] - seq.index[end]) % max(seq.n_beams, 1) <= corner_beams
    corner = near & turns & (to_end <= corner_distance) & (to_start <= corner_distance)
    end_off = np.abs(point_residuals(seq.x, seq.y, lines.rho, lines.alpha, end, second))
    start_off = np.abs(point_residuals(seq.x, seq.y, lines.rho, lines.alpha, start, first))
    continues = near & ~turns & (end_off <= corner_distance) & (start_off <= corner_distance)
    at = _nearest_return(seq, cx, cy, a[first], end, start, b[second], corner_beams)
    corners = np.unique(seq.index[at[corner]])
    if group is not None:
        return corners, _EMPTY
    return corners, np.unique(seq.index[end[~corner & ~continues]])


def _nearest_return(
    seq: Sequence,
    cx: np.ndarray,
    cy: np.ndarray,
    low: np.ndarray,
    end: np.ndarray,
    start: np.ndarray,
    high: np.ndarray,
    reach: int,
) -> np.ndarray:
    """Position nearest ``(cx, cy)`` among ``end - reach .. start + reach`` (within ``low..high``).

    A pair that wraps (the last segment and the first) counts on past the end of
    the sequence.
    """
    if end.size == 0:
        return end
    n = len(seq)
    wraps = start < end
    start = np.where(wraps, start + n, start)
    high = np.where(wraps, high + n, high)
    offsets = np.arange(-reach, reach + 1 + int(np.max(start - end)))
    candidate = end[:, None] + offsets[None, :]
    inside = (candidate >= low[:, None]) & (candidate <= high[:, None])
    candidate = np.where(inside, candidate, end[:, None]) % n
    distance = np.hypot(seq.x[candidate] - cx[:, None], seq.y[candidate] - cy[:, None])
    distance = np.where(np.isnan(distance), np.inf, distance)
    return candidate[np.arange(end.size), np.argmin(distance, axis=1)]


def drop_small(
    seq: Sequence,
    a: np.ndarray,
    b: np.ndarray,
    group: np.ndarray,
    *,
    min_points: int,
    min_length: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs with at least ``min_points`` points and an end-to-end length of ``min_length``."""
    length = np.hypot(seq.x[b] - seq.x[a], seq.y[b] - seq.y[a])
    keep = (b - a + 1 >= max(min_points, 2)) & (length >= min_length)
    return a[keep], b[keep], group[keep]


def finish(
    seq: Sequence,
    a: np.ndarray,
    b: np.ndarray,
    group: np.ndarray,
    *,
    clusters: Clusters | None,
    ring: bool,
    outliers: np.ndarray,
    angle_min: float,
    method: str,
    params: Mapping[str, Any],
) -> Extraction:
    """Drop small runs, find corners (and breakpoints) and assemble the extraction.

    ``clusters`` is the method's clustering (its breakpoints are reported and
    corners stay inside clusters), or ``None`` for a method on the whole scan.
    """
    a, b, group = drop_small(
        seq, a, b, group, min_points=params["min_points"], min_length=params["min_length"]
    )
    moments = Moments(seq.x, seq.y)
    full = is_full_circle(seq.n_beams, seq.step)
    corners, derived = segment_events(
        seq,
        moments,
        a,
        b,
        group=None if clusters is None else group,
        wrap=ring if clusters is not None else full,
        corner_beams=params["corner_beams"],
        corner_distance=params["corner_distance"],
        corner_angle=params["corner_angle"],
    )
    breakpoints = derived if clusters is None else clusters.breakpoints
    return assemble(
        seq,
        a,
        b,
        fit="tls",
        moments=moments,
        corners=corners,
        breakpoints=np.unique(breakpoints).astype(np.intp),
        outliers=np.unique(outliers).astype(np.intp),
        angle_min=angle_min,
        range_sigma=params["range_sigma"],
        method=method,
        params=params,
    )
