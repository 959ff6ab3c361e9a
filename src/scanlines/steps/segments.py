"""Steps shared by the comparison methods: cutting, growing and joining runs of points.

A *run* is an inclusive interval ``[a, b]`` of sequence positions (see
:mod:`scanlines.steps.points`); ``group`` numbers the cluster (or the line) each run
came from. The steps are compiled kernels (:mod:`scanlines._jit`) that the methods
chain into one kernel per scan; the functions named in the sections below are
their thin numpy-facing wrappers, for methods that still run as Python code.

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
    farthest from the chord (see :func:`split_runs`), and the runs are split
    depth first. The split point joins the part whose line (fitted without it)
    it is nearer, so no point is lost.
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

from scanlines._jit import jit
from scanlines.extraction import Extraction
from scanlines.params import Param, int_at_least, number
from scanlines.scan import is_full_circle
from scanlines.steps.assemble import assemble_runs, from_arrays
from scanlines.steps.breakpoints import (
    ABD,
    ADAPTIVE,
    BREAKPOINT_PARAMS,
    FIXED,
    MAX_BRIDGED_GAP,
    RULE_CODES,
    Clusters,
    break_beams,
    break_flags,
    cluster_bounds,
    noise_rule,
    rule_array,
    seam_rotation,
)
from scanlines.steps.corners import ring_anchor
from scanlines.steps.denoise import MIN_NOISE_SIGMA, noise_from_ranges
from scanlines.steps.fit import (
    TLS,
    Lines,
    Moments,
    covariances,
    fit_many,
    line_intersection,
    prefix_moments,
    run_labels,
    tls_lines,
    tls_run,
)
from scanlines.steps.points import Sequence, rotate

__all__ = [
    "BRIDGE_RETURNS",
    "EVENT_PARAMS",
    "LITERAL_CLUSTERING",
    "LineFinder",
    "cluster_returns",
    "cluster_sequence",
    "consensus_extraction",
    "consensus_segments",
    "drop_small",
    "finish",
    "finish_runs",
    "inlier_runs",
    "line_difference",
    "line_intersections",
    "merge_chi_square",
    "merge_runs_chi_square",
    "pair_chi_square",
    "remove_positions",
    "segment_events",
    "settings",
    "split_runs",
    "split_runs_at_farthest",
    "valid_returns",
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

RING_WINDOW = 5
"""Points fitted on each side of the turn angle that anchors a ring (a full circle
without any gap is cut at its strongest corner)."""

# --------------------------------------------------------------------------- settings
# The kernels take a method's parameters as one float array; these name its slots.
(
    RULE_KIND, K, NOISE_K, LINE_K, ABD_LAMBDA, PDBS_C0, JUMP_DISTANCE,
    MIN_POINTS, MIN_LENGTH, RANGE_SIGMA, CORNER_BEAMS, CORNER_DISTANCE, CORNER_ANGLE,
    SPLIT_DISTANCE, SPLIT_REFERENCE, OUTLIER_DISTANCE, MERGE_CHI2, N_SETTINGS,
) = range(18)  # fmt: skip
NO_RULE = -1.0
"""``RULE_KIND`` of ``breakpoints="none"``: one cluster of every return."""
CHORD, FIT = 0, 1
REFERENCE_CODES = {"chord": CHORD, "fit": FIT}


def settings(params: Mapping[str, Any], reference: str = "chord") -> np.ndarray:
    """The kernels' form of a method's resolved ``params`` (angles in radians).

    ``reference`` is the split's distance reference (``"chord"`` or ``"fit"``);
    parameters a method does not have (``split_distance``, ``outlier_distance``,
    ``merge_chi2``) are NaN.
    """
    s = np.full(N_SETTINGS, math.nan)
    name = params["breakpoints"]
    s[RULE_KIND] = NO_RULE if name == NO_CLUSTERING else RULE_CODES[name]
    s[K], s[PDBS_C0], s[JUMP_DISTANCE] = params["k"], params["pdbs_c0"], params["jump_distance"]
    s[NOISE_K], s[LINE_K] = params.get("noise_k", 0.0), params.get("line_k", 0.0)
    s[ABD_LAMBDA] = math.radians(params["abd_lambda"])
    s[MIN_POINTS], s[MIN_LENGTH] = params["min_points"], params["min_length"]
    s[RANGE_SIGMA] = params["range_sigma"]
    s[CORNER_BEAMS], s[CORNER_DISTANCE] = params["corner_beams"], params["corner_distance"]
    s[CORNER_ANGLE] = math.radians(params["corner_angle"])
    s[SPLIT_REFERENCE] = REFERENCE_CODES[reference]
    for slot, key in (
        (SPLIT_DISTANCE, "split_distance"),
        (OUTLIER_DISTANCE, "outlier_distance"),
        (MERGE_CHI2, "merge_chi2"),
    ):
        s[slot] = params.get(key, math.nan)
    return s


# --------------------------------------------------------------------------- clustering


@jit
def valid_returns(ranges, valid, cos, sin):
    """``index, r, x, y`` of the beams with a return (local frame: bearing tables ``cos, sin``)."""
    count = 0
    for i in range(valid.shape[0]):
        count += valid[i]
    index = np.empty(count, dtype=np.int64)
    r = np.empty(count)
    x = np.empty(count)
    y = np.empty(count)
    p = 0
    for i in range(valid.shape[0]):
        if valid[i]:
            index[p], r[p] = i, ranges[i]
            x[p], y[p] = ranges[i] * cos[i], ranges[i] * sin[i]
            p += 1
    return index, r, x, y


@jit
def beam_gaps(index: np.ndarray, n_beams: int) -> np.ndarray:
    """Beams between consecutive positions (a rotated full circle wraps once)."""
    gap = np.empty(max(index.shape[0] - 1, 0), dtype=np.int64)
    for p in range(gap.shape[0]):
        gap[p] = (index[p + 1] - index[p]) % n_beams
    return gap


@jit
def clustering_rule(s: np.ndarray, r: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """The breakpoint rule of settings ``s`` in array form, its noise terms from ranges ``r``.

    The noise is estimated (from the whole scan) only when the rule uses it.
    ``breakpoints="none"`` gives a rule that cuts at missing beams only.
    """
    kind = s[RULE_KIND]
    if kind == NO_RULE:
        return rule_array(FIXED, s[K], 0.0, 0.0, s[ABD_LAMBDA], s[PDBS_C0], math.inf)
    sigma = 0.0
    noisy_rule = kind in (ADAPTIVE, ABD) and s[NOISE_K] > 0.0
    if noisy_rule or s[LINE_K] > 0.0:
        n = r.shape[0]
        sigma = MIN_NOISE_SIGMA
        if n:
            sigma = noise_from_ranges(r, gap, np.zeros(1, np.int64), np.full(1, n - 1, np.int64))
    return noise_rule(
        int(kind), s[K], s[NOISE_K], s[LINE_K], s[ABD_LAMBDA], s[PDBS_C0], s[JUMP_DISTANCE], sigma
    )


@jit
def rotated(values: np.ndarray, shift: int) -> np.ndarray:
    """``values`` rotated so that position ``shift`` comes first."""
    return np.concatenate((values[shift:], values[:shift]))


@jit
def cluster_returns(index, r, x, y, n_beams: int, step: float, full_circle: bool, s):
    """Kernel of :func:`cluster_sequence` on the returns' arrays.

    Returns ``index, r, x, y`` (rotated for a full circle), the rotation
    ``shift`` (the old position now first), the clusters' inclusive bounds
    ``start, end``, the breakpoint beams and whether the scan is one closed ring.
    """
    n = index.shape[0]
    none = np.zeros(0, dtype=np.int64)
    rule = clustering_rule(s, r, beam_gaps(index, n_beams))
    whole = s[RULE_KIND] == NO_RULE
    if n == 0 and not whole:
        return index, r, x, y, 0, none, none.copy(), none.copy(), False
    shift, seam, ring = 0, False, False
    if full_circle and n >= 3:
        shift, seam, ring = seam_rotation(
            x, y, r, index, beam_gaps(index, n_beams), n_beams, step, rule
        )
        if ring:
            shift = ring_anchor(x, y, RING_WINDOW)
        if shift:
            index, r, x, y = (
                rotated(index, shift),
                rotated(r, shift),
                rotated(x, shift),
                rotated(y, shift),
            )
    if ring or whole:
        start, end = np.zeros(1, np.int64), np.full(1, n - 1, np.int64)
        return index, r, x, y, shift, start, end, none, ring
    start, end = cluster_bounds(break_flags(x, y, r, beam_gaps(index, n_beams), step, rule))
    return index, r, x, y, shift, start, end, break_beams(index, end, seam), False


def cluster_sequence(seq: Sequence, params: Mapping[str, Any]) -> tuple[Sequence, Clusters, bool]:
    """Cluster ``seq`` by the method's ``breakpoints`` rule, joining the seam of full circles.

    ``breakpoints="none"`` (methods that work on the whole scan) returns one
    cluster over every return; a full circle is still rotated to start after a gap
    of missing beams (or, without any, at its strongest corner), so that no run
    needs to cross the end of the sequence. The adaptive and ABD rules' noise
    margin and the line-continuation bridge use the range noise estimated from
    the scan.

    Returns the (possibly rotated) sequence, its clusters and whether the scan is
    one closed ring (a full circle without any break).
    """
    *_, shift, start, end, breakpoints, ring = cluster_returns(
        *_returns(seq),
        seq.n_beams,
        seq.step,
        is_full_circle(seq.n_beams, seq.step),
        settings(params),
    )
    if shift or ring:
        seq = rotate(seq, int(shift))
    return seq, Clusters(start, end, breakpoints), bool(ring)


def _returns(seq: Sequence) -> tuple[np.ndarray, ...]:
    """``index, r, x, y`` of ``seq`` as the kernels take them."""
    return (
        np.ascontiguousarray(seq.index, dtype=np.int64),
        *(np.ascontiguousarray(v, dtype=np.float64) for v in (seq.r, seq.x, seq.y)),
    )


def _ints(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.int64)


def _floats(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


# --------------------------------------------------------------------------- distances


@jit(inline=True)
def chord_distance(x: np.ndarray, y: np.ndarray, a: int, b: int, p: int) -> float:
    """Distance of point ``p`` to the chord from point ``a`` to point ``b``.

    The chord is the segment between the two points: a point whose foot lies
    beyond an end is measured to that end. For a cluster that nearly closes on
    itself (a room seen all round) the chord is short and its line points
    anywhere; measured to the segment, the farthest point is the far corner,
    not an arbitrary point of the side opposite the chord.
    """
    dx, dy = x[b] - x[a], y[b] - y[a]
    px, py = x[p] - x[a], y[p] - y[a]
    length2 = dx * dx + dy * dy
    t = 0.0
    if length2 > 0.0:
        t = (px * dx + py * dy) / length2
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    return math.hypot(px - t * dx, py - t * dy)


@jit
def _chord_distances(x, y, a, b, position, run):
    out = np.empty(position.shape[0])
    for i in range(position.shape[0]):
        out[i] = chord_distance(x, y, a[run[i]], b[run[i]], position[i])
    return out


def chord_distances(
    x: np.ndarray,
    y: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    position: np.ndarray,
    run: np.ndarray,
) -> np.ndarray:
    """Distance of each labelled point to the chord of its run (see :func:`chord_distance`)."""
    return _chord_distances(_floats(x), _floats(y), _ints(a), _ints(b), _ints(position), _ints(run))


@jit(inline=True)
def line_residual(x: np.ndarray, y: np.ndarray, p: int, rho: float, alpha: float) -> float:
    """Orthogonal distance of point ``p`` to the line ``(rho, alpha)``."""
    return abs(x[p] * math.cos(alpha) + y[p] * math.sin(alpha) - rho)


# --------------------------------------------------------------------------- splitting


@jit(inline=True)
def farthest_from_chord(x: np.ndarray, y: np.ndarray, a: int, b: int) -> tuple[float, int]:
    """Largest distance of an interior point of run ``[a, b]`` from its chord, and that point.

    The first of equally far points; ``(-inf, a)`` without an interior point.
    """
    worst, at = -math.inf, a
    for p in range(a + 1, b):
        distance = chord_distance(x, y, a, b, p)
        if distance > worst:  # NaN never wins
            worst, at = distance, p
    return worst, at


@jit(inline=True)
def farthest_from_line(x, y, table, ox: float, oy: float, a: int, b: int) -> float:
    """Largest distance of an interior point of run ``[a, b]`` from the run's TLS line."""
    rho, alpha, _ = tls_run(table, ox, oy, a, b)
    c, s = math.cos(alpha), math.sin(alpha)
    worst = -math.inf
    for p in range(a + 1, b):
        distance = abs(x[p] * c + y[p] * s - rho)
        if distance > worst:
            worst = distance
    return worst


@jit(inline=True)
def split_side(x, y, table, ox: float, oy: float, a: int, b: int, at: int) -> int:
    """Last position of the first part when run ``[a, b]`` is split at ``at``: ``at`` or ``at - 1``.

    The split point joins the part whose TLS line (fitted without it) it is
    nearer; next to an end (one point on that side) it joins that short side, the
    long side being the one it does not fit.
    """
    if at - a < 2:
        return at
    if b - at < 2:
        return at - 1
    rho, alpha, _ = tls_run(table, ox, oy, a, at - 1)
    to_left = line_residual(x, y, at, rho, alpha)
    rho, alpha, _ = tls_run(table, ox, oy, at + 1, b)
    to_right = line_residual(x, y, at, rho, alpha)
    return at - 1 if to_left > to_right else at


@jit
def split_runs_at_farthest(x, y, table, ox, oy, a, b, group, threshold: float, reference: int):
    """Kernel of :func:`split_runs`: each run split recursively, depth first.

    Returns ``a, b, group`` of the final runs, each input run's parts in order
    (so sequence order for disjoint runs given in order).
    """
    capacity = 0
    for k in range(a.shape[0]):
        capacity += max(b[k] - a[k] + 1, 1)  # every final run holds a point of its input
    out_a = np.empty(capacity, dtype=np.int64)
    out_b = np.empty(capacity, dtype=np.int64)
    out_group = np.empty(capacity, dtype=np.int64)
    # The stack holds runs still to test; every one of them ends as one output or more.
    stack_a = np.empty(capacity, dtype=np.int64)
    stack_b = np.empty(capacity, dtype=np.int64)
    stack_group = np.empty(capacity, dtype=np.int64)
    top = 0
    for k in range(a.shape[0] - 1, -1, -1):
        stack_a[top], stack_b[top], stack_group[top] = a[k], b[k], group[k]
        top += 1
    count = 0
    while top:
        top -= 1
        lo, hi, g = stack_a[top], stack_b[top], stack_group[top]
        if hi - lo >= 2:
            worst, at = farthest_from_chord(x, y, lo, hi)
            if reference == FIT:
                worst = farthest_from_line(x, y, table, ox, oy, lo, hi)
            if worst > threshold:
                cut = split_side(x, y, table, ox, oy, lo, hi, at)
                stack_a[top], stack_b[top], stack_group[top] = cut + 1, hi, g
                stack_a[top + 1], stack_b[top + 1], stack_group[top + 1] = lo, cut, g
                top += 2
                continue
        out_a[count], out_b[count], out_group[count] = lo, hi, g
        count += 1
    return out_a[:count], out_b[:count], out_group[:count]


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
    ox, oy = moments.origin
    a, b, group = split_runs_at_farthest(
        _floats(seq.x), _floats(seq.y), moments.table, ox, oy, _ints(a), _ints(b), _ints(group),
        float(threshold), REFERENCE_CODES[reference],
    )  # fmt: skip
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


@jit(inline=True)
def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to ``(-pi, pi]``."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


@jit(inline=True)
def hesse_difference(rho_1: float, alpha_1: float, rho_2: float, alpha_2: float):
    """``(rho_1 - rho_2, alpha_1 - alpha_2)`` of two Hesse lines (see :func:`line_difference`)."""
    direct = wrap_angle(alpha_1 - alpha_2)
    flipped = wrap_angle(alpha_1 - alpha_2 + math.pi)
    if abs(flipped) < abs(direct):
        return rho_1 + rho_2, flipped
    return rho_1 - rho_2, direct


@jit
def _line_differences(rho_1, alpha_1, rho_2, alpha_2):
    d_rho = np.empty(rho_1.shape[0])
    d_alpha = np.empty(rho_1.shape[0])
    for i in range(rho_1.shape[0]):
        d_rho[i], d_alpha[i] = hesse_difference(rho_1[i], alpha_1[i], rho_2[i], alpha_2[i])
    return d_rho, d_alpha


def line_difference(
    rho_1: np.ndarray, alpha_1: np.ndarray, rho_2: np.ndarray, alpha_2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(rho_1 - rho_2, alpha_1 - alpha_2)`` with the angle wrapped to ``(-pi, pi]``.

    Hesse parameters are ambiguous for a line through the origin (``(rho, alpha)``
    and ``(-rho, alpha + pi)``); of the two the one with the smaller angle
    difference is used.
    """
    values = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (rho_1, alpha_1, rho_2, alpha_2))
    )
    d_rho, d_alpha = _line_differences(*(np.ascontiguousarray(v.ravel()) for v in values))
    return d_rho.reshape(values[0].shape), d_alpha.reshape(values[0].shape)


@jit(inline=True)
def chi_square(rho_1, alpha_1, rho_2, alpha_2, covariance_1, covariance_2) -> float:
    """``dL^T (P_1 + P_2)^-1 dL`` of two lines; NaN where the sum is singular."""
    d_rho, d_alpha = hesse_difference(rho_1, alpha_1, rho_2, alpha_2)
    p = covariance_1[0, 0] + covariance_2[0, 0]
    q = covariance_1[0, 1] + covariance_2[0, 1]
    s = covariance_1[1, 1] + covariance_2[1, 1]
    det = p * s - q * q
    if not det > 0.0:  # degenerate runs carry inf/NaN covariances
        return math.nan
    return (s * d_rho * d_rho - 2.0 * q * d_rho * d_alpha + p * d_alpha * d_alpha) / det


@jit
def _pair_chi_squares(rho, alpha, covariance, first, second):
    out = np.empty(first.shape[0])
    for i in range(first.shape[0]):
        j, k = first[i], second[i]
        out[i] = chi_square(rho[j], alpha[j], rho[k], alpha[k], covariance[j], covariance[k])
    return out


def pair_chi_square(
    lines: Lines, covariance: np.ndarray, first: np.ndarray, second: np.ndarray
) -> np.ndarray:
    """``dL^T (P_1 + P_2)^-1 dL`` of line pairs; NaN where the sum is singular."""
    return _pair_chi_squares(
        _floats(lines.rho), _floats(lines.alpha), _floats(covariance), _ints(first), _ints(second)
    )


@jit
def run_covariance(x, y, r, rho: float, alpha: float, a: int, b: int, range_sigma: float):
    """Covariance of the line ``(rho, alpha)`` of run ``[a, b]`` (shape (2, 2))."""
    position, run = run_labels(np.full(1, a), np.full(1, b), x.shape[0])
    return covariances(x, y, r, np.full(1, rho), np.full(1, alpha), position, run, range_sigma)[0]


@jit
def merge_runs_chi_square(x, y, r, table, ox, oy, a, b, group, range_sigma, threshold):
    """Kernel of :func:`merge_chi_square` (returns new arrays)."""
    a, b, group = a.copy(), b.copy(), group.copy()
    m = a.shape[0]
    rho, alpha, _ = fit_many(TLS, table, ox, oy, a, b)
    position, run = run_labels(a, b, x.shape[0])
    covariance = covariances(x, y, r, rho, alpha, position, run, range_sigma)
    while m >= 2:
        best, best_value = -1, math.inf
        for k in range(m - 1):
            if group[k] != group[k + 1]:
                continue
            value = chi_square(
                rho[k], alpha[k], rho[k + 1], alpha[k + 1], covariance[k], covariance[k + 1]
            )
            if value != value:
                value = math.inf
            if best < 0 or value < best_value:
                best, best_value = k, value
        if best < 0 or not best_value < threshold:
            break
        b[best] = b[best + 1]
        for k in range(best + 1, m - 1):  # delete run best + 1
            a[k], b[k], group[k] = a[k + 1], b[k + 1], group[k + 1]
            rho[k], alpha[k], covariance[k] = rho[k + 1], alpha[k + 1], covariance[k + 1]
        m -= 1
        rho[best], alpha[best], _ = tls_run(table, ox, oy, a[best], b[best])
        covariance[best] = run_covariance(
            x, y, r, rho[best], alpha[best], a[best], b[best], range_sigma
        )
    return a[:m], b[:m], group[:m]


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
    ox, oy = moments.origin
    x, y, r = _floats(seq.x), _floats(seq.y), _floats(seq.r)
    return merge_runs_chi_square(
        x, y, r, moments.table, ox, oy, _ints(a), _ints(b), _ints(group),
        float(range_sigma), float(threshold),
    )  # fmt: skip


# --------------------------------------------------------------------------- events


@jit
def _line_intersections(rho, alpha, first, second):
    x = np.empty(first.shape[0])
    y = np.empty(first.shape[0])
    for i in range(first.shape[0]):
        j, k = first[i], second[i]
        x[i], y[i] = line_intersection(rho[j], alpha[j], rho[k], alpha[k])
    return x, y


def line_intersections(
    lines: Lines, first: np.ndarray, second: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Intersection of line pairs (NaN for parallel lines)."""
    return _line_intersections(
        _floats(lines.rho), _floats(lines.alpha), _ints(first), _ints(second)
    )


@jit
def sorted_distinct(values: np.ndarray) -> np.ndarray:
    """The distinct values of an integer array, ascending."""
    ordered = np.sort(values)
    count = min(ordered.shape[0], 1)
    for i in range(1, ordered.shape[0]):
        if ordered[i] != ordered[count - 1]:
            ordered[count] = ordered[i]
            count += 1
    return ordered[:count]


@jit(inline=True)
def nearest_return(
    x, y, cx: float, cy: float, low: int, end: int, start: int, high: int, reach: int, widest: int
) -> int:
    """Position nearest ``(cx, cy)`` among ``end - reach .. start + reach`` (within ``low..high``).

    A pair that wraps (the last segment and the first) counts on past the end of
    the sequence. The candidates run on to ``end + reach + widest``, ``widest``
    the most positions between the facing ends of any pair of the scan (as the
    vectorised implementation had it); those beyond ``high`` count as ``end``.
    """
    n = x.shape[0]
    if start < end:
        high += n
    best, best_distance = -1, math.inf
    for offset in range(-reach, reach + 1 + widest):
        candidate = end + offset
        if candidate < low or candidate > high:
            candidate = end
        candidate %= n
        distance = math.hypot(x[candidate] - cx, y[candidate] - cy)
        if distance != distance:
            distance = math.inf
        if best < 0 or distance < best_distance:
            best, best_distance = candidate, distance
    return best


@jit
def run_events(
    x,
    y,
    index,
    n_beams,
    table,
    ox,
    oy,
    a,
    b,
    group,
    clustered,
    wrap,
    corner_beams,
    corner_distance,
    corner_angle,
):
    """Kernel of :func:`segment_events`: ``corners, breakpoints`` (sorted distinct beams).

    ``clustered``: only segments of one ``group`` can meet and no breakpoints are
    derived; ``corner_angle`` in radians.
    """
    none = np.zeros(0, dtype=np.int64)
    m = a.shape[0]
    if m == 0 or (m == 1 and not wrap):
        return none, none.copy()
    pairs = m if wrap and m >= 2 else m - 1
    first = np.empty(pairs, dtype=np.int64)
    count = widest = 0
    for k in range(pairs):
        following = (k + 1) % m
        if clustered and group[k] != group[following]:
            continue
        first[count] = k
        count += 1
        span = a[following] - b[k]
        widest = max(widest, span + x.shape[0] if span < 0 else span)
    rho, alpha, _ = fit_many(TLS, table, ox, oy, a, b)
    reach = int(corner_beams)
    corners = np.empty(count, dtype=np.int64)
    jumps = np.empty(count, dtype=np.int64)
    n_corners = n_jumps = 0
    for c in range(count):
        i = first[c]
        j = (i + 1) % m
        end, start = b[i], a[j]
        _, turn = hesse_difference(rho[i], alpha[i], rho[j], alpha[j])
        turns = abs(turn) >= corner_angle
        cx, cy = line_intersection(rho[i], alpha[i], rho[j], alpha[j])
        to_end = math.hypot(x[end] - cx, y[end] - cy)
        to_start = math.hypot(x[start] - cx, y[start] - cy)
        near = (index[start] - index[end]) % max(n_beams, 1) <= corner_beams
        if near and turns and to_end <= corner_distance and to_start <= corner_distance:
            at = nearest_return(x, y, cx, cy, a[i], end, start, b[j], reach, widest)
            corners[n_corners] = index[at]
            n_corners += 1
            continue
        if clustered:
            continue
        end_off = line_residual(x, y, end, rho[j], alpha[j])
        start_off = line_residual(x, y, start, rho[i], alpha[i])
        if not (near and not turns and end_off <= corner_distance and start_off <= corner_distance):
            jumps[n_jumps] = index[end]
            n_jumps += 1
    return sorted_distinct(corners[:n_corners]), sorted_distinct(jumps[:n_jumps])


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
    a = _ints(a)
    ox, oy = moments.origin
    return run_events(
        _floats(seq.x), _floats(seq.y), _ints(seq.index), int(seq.n_beams), moments.table, ox, oy,
        a, _ints(b), _ints(a if group is None else group), group is not None, bool(wrap),
        float(corner_beams), float(corner_distance), math.radians(corner_angle),
    )  # fmt: skip


# --------------------------------------------------------------------------- assembly


@jit
def drop_small_runs(x, y, a, b, group, min_points: float, min_length: float):
    """Kernel of :func:`drop_small`."""
    kept_a, kept_b, kept_group = a.copy(), b.copy(), group.copy()
    count = 0
    for k in range(a.shape[0]):
        length = math.hypot(x[b[k]] - x[a[k]], y[b[k]] - y[a[k]])
        if b[k] - a[k] + 1 >= max(min_points, 2.0) and length >= min_length:
            kept_a[count], kept_b[count], kept_group[count] = a[k], b[k], group[k]
            count += 1
    return kept_a[:count], kept_b[:count], kept_group[:count]


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
    return drop_small_runs(
        _floats(seq.x), _floats(seq.y), _ints(a), _ints(b), _ints(group),
        float(min_points), float(min_length),
    )  # fmt: skip


@jit
def finish_runs(
    index,
    r,
    x,
    y,
    n_beams,
    full_circle,
    table,
    ox,
    oy,
    a,
    b,
    group,
    clustered,
    ring,
    breakpoints,
    outliers,
    angle_min,
    s,
):
    """Kernel of :func:`finish`: the result arrays, as
    :func:`~scanlines.steps.assemble.assemble_runs` returns them.

    ``table, ox, oy`` are the prefix moments of ``x, y``; ``clustered`` whether
    ``breakpoints`` come from the method's clustering (else they are derived
    from the jumps between segments).
    """
    a, b, group = drop_small_runs(x, y, a, b, group, s[MIN_POINTS], s[MIN_LENGTH])
    corners, jumps = run_events(
        x, y, index, n_beams, table, ox, oy, a, b, group, clustered,
        ring if clustered else full_circle, s[CORNER_BEAMS], s[CORNER_DISTANCE], s[CORNER_ANGLE],
    )  # fmt: skip
    if not clustered:
        breakpoints = jumps
    return assemble_runs(
        index, x, y, r, a, b, TLS, table, ox, oy, angle_min, s[RANGE_SIGMA],
        sorted_distinct(breakpoints), corners, sorted_distinct(outliers),
    )  # fmt: skip


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
    index, r, x, y = _returns(seq)
    table, ox, oy = prefix_moments(x, y)
    arrays = finish_runs(
        index, r, x, y, int(seq.n_beams), is_full_circle(seq.n_beams, seq.step), table, ox, oy,
        _ints(a), _ints(b), _ints(group), clusters is not None, bool(ring),
        _EMPTY.astype(np.int64) if clusters is None else _ints(clusters.breakpoints),
        _ints(outliers), float(angle_min), settings(params),
    )  # fmt: skip
    return from_arrays(arrays, method, params)
