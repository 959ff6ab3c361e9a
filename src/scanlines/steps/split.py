"""Splitting runs of points: at the point farthest from the chord, at a residual bound,
and at the corners a sweep chose.

``split_at_farthest``  the recursive split of iterative end-point fit [1]_ [2]_
                       (``reference`` :data:`CHORD`: a run is split while a point is
                       farther than the threshold from the chord from its first to its
                       last point) and of split-and-merge [3]_ (:data:`LINE`: ... from
                       the run's total-least-squares line). Either way the cut is at the
                       interior point farthest from the chord, runs are split depth
                       first, and the split point joins the part whose line (fitted
                       without it) it is nearer, so no point is lost.
``split_by_residual``  a hard bound: while a point of a run lies farther than its
                       tolerance from its line, the run is cut at its worst point (as
                       iterative end-point fit does) and that point is left out of both
                       parts.
``cut_at``, ``refine_cuts``  the runs of clusters cut at chosen corners, and each cut
                       moved by one position where that fits better.

References
----------
.. [1] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973 (iterative end-point fit).
.. [2] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE Trans.
   Computers C-23(8), 860-870, 1974 (split-and-merge).
.. [3] V. Nguyen, A. Martinelli, N. Tomatis and R. Siegwart, "A comparison of line
   extraction algorithms using 2D laser rangefinder for indoor mobile robotics",
   IEEE/RSJ IROS 2005, 1929-1934.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.fit import fit_run, run_cost, tls_run

__all__ = [
    "CHORD",
    "LINE",
    "REFERENCE_CODES",
    "chord_distance",
    "cut_at",
    "line_residual",
    "refine_cuts",
    "split_at_farthest",
    "split_by_residual",
]

CHORD, LINE = 0, 1
REFERENCE_CODES = {"chord": CHORD, "fit": LINE}


@kernel
def chord_distance(x, y, a, b, p):
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


@kernel
def line_residual(x, y, p, rho, alpha):
    """Orthogonal distance of point ``p`` to the line ``(rho, alpha)``."""
    return abs(x[p] * math.cos(alpha) + y[p] * math.sin(alpha) - rho)


@kernel
def farthest_from_chord(x, y, a, b):
    """Largest distance of an interior point of run ``[a, b]`` from its chord, and that point.

    The first of equally far points; ``(-inf, a)`` without an interior point.
    """
    worst, at = -math.inf, a
    for p in range(a + 1, b):
        distance = chord_distance(x, y, a, b, p)
        if distance > worst:  # NaN never wins
            worst, at = distance, p
    return worst, at


@kernel
def farthest_from_line(x, y, moments, a, b):
    """Largest distance of an interior point of run ``[a, b]`` from the run's TLS line."""
    rho, alpha, _ = tls_run(moments, a, b)
    c, s = math.cos(alpha), math.sin(alpha)
    worst = -math.inf
    for p in range(a + 1, b):
        distance = abs(x[p] * c + y[p] * s - rho)
        if distance > worst:
            worst = distance
    return worst


@kernel
def split_side(x, y, moments, a, b, at):
    """Last position of the first part when run ``[a, b]`` is split at ``at``: ``at`` or ``at - 1``.

    The split point joins the part whose TLS line (fitted without it) it is
    nearer; next to an end (one point on that side) it joins that short side, the
    long side being the one it does not fit.
    """
    if at - a < 2:
        return at
    if b - at < 2:
        return at - 1
    rho, alpha, _ = tls_run(moments, a, at - 1)
    to_left = line_residual(x, y, at, rho, alpha)
    rho, alpha, _ = tls_run(moments, at + 1, b)
    to_right = line_residual(x, y, at, rho, alpha)
    return at - 1 if to_left > to_right else at


@kernel
def split_at_farthest(x, y, moments, a, b, group, threshold, reference):
    """Each run ``[a, b]`` (of ``group``) split recursively, depth first (module docstring).

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
            if reference == LINE:
                worst = farthest_from_line(x, y, moments, lo, hi)
            if worst > threshold:
                cut = split_side(x, y, moments, lo, hi, at)
                stack_a[top], stack_b[top], stack_group[top] = cut + 1, hi, g
                stack_a[top + 1], stack_b[top + 1], stack_group[top + 1] = lo, cut, g
                top += 2
                continue
        out_a[count], out_b[count], out_group[count] = lo, hi, g
        count += 1
    return out_a[:count], out_b[:count], out_group[:count]


@kernel
def split_by_residual(x, y, fit, moments, a, b, cluster, tolerance, min_points):
    """Cut runs at their worst point until every point is within its ``tolerance``.

    ``tolerance`` is per point (metres); the worst point of a run is the one farthest
    from the run's line relative to its tolerance. Each run is split recursively, left
    part first; parts shorter than ``min_points`` are dropped. When the worst point lies
    in a run's last few points (its cut would only trim an end shorter than
    ``min_points``) and the run also bends away from the chord of its ends by more than
    the tolerance (an arc, whose fitted line is farthest from its ends), the run is cut
    where it is farthest from that chord instead: arcs become chains of segments in
    O(n log n), rather than losing a point at a time from their ends in O(n^2). A stray
    end point is still trimmed. Terminates because every cut removes a point or halves
    a run.
    """
    out_a = np.empty(x.shape[0] + 1, dtype=np.int64)
    out_b = np.empty(x.shape[0] + 1, dtype=np.int64)
    out_cluster = np.empty(x.shape[0] + 1, dtype=np.int64)
    count = 0
    stack_a = np.empty(x.shape[0] + 1, dtype=np.int64)
    stack_b = np.empty(x.shape[0] + 1, dtype=np.int64)
    shortest = max(min_points, 1)
    for k in range(a.shape[0]):
        stack_a[0], stack_b[0] = a[k], b[k]
        top = 1
        while top:
            top -= 1
            lo, hi = stack_a[top], stack_b[top]
            if hi - lo + 1 < shortest:
                continue
            rho, alpha, _ = fit_run(fit, moments, lo, hi)
            worst, worst_at = _farthest_from_line(
                x, y, tolerance, lo, hi, math.cos(alpha), math.sin(alpha), rho
            )
            if worst <= 1.0:
                out_a[count], out_b[count], out_cluster[count] = lo, hi, cluster[k]
                count += 1
                continue
            if worst_at - lo < shortest or hi - worst_at < shortest:
                bend, bend_at = _farthest_from_chord(x, y, tolerance, lo, hi)
                if bend > 1.0 and bend_at - lo >= shortest and hi - bend_at >= shortest:
                    stack_a[top], stack_b[top] = bend_at + 1, hi
                    stack_a[top + 1], stack_b[top + 1] = lo, bend_at
                    top += 2
                    continue
            stack_a[top], stack_b[top] = worst_at + 1, hi  # right part after the left
            stack_a[top + 1], stack_b[top + 1] = lo, worst_at - 1
            top += 2
    return out_a[:count], out_b[:count], out_cluster[:count]


@kernel
def _farthest_from_line(x, y, tolerance, lo, hi, c, s, rho):
    """The largest distance of points ``lo..hi`` from the line ``(rho, alpha)`` (given as
    ``c = cos alpha, s = sin alpha``) in units of each point's ``tolerance``, and where;
    NaN distances never count."""
    worst, worst_at = -1.0, lo
    for p in range(lo, hi + 1):
        distance = abs(x[p] * c + y[p] * s - rho) / tolerance[p]
        if distance > worst:
            worst, worst_at = distance, p
    return worst, worst_at


@kernel
def _farthest_from_chord(x, y, tolerance, lo, hi):
    """The largest distance of points ``lo..hi`` from the chord joining the two, in units
    of each point's ``tolerance``, and where."""
    dx, dy = x[hi] - x[lo], y[hi] - y[lo]
    length = math.sqrt(dx * dx + dy * dy)
    if length == 0.0:
        return 0.0, lo
    worst, worst_at = -1.0, lo
    for p in range(lo, hi + 1):
        distance = abs((x[p] - x[lo]) * dy - (y[p] - y[lo]) * dx) / length / tolerance[p]
        if distance > worst:
            worst, worst_at = distance, p
    return worst, worst_at


@kernel
def cut_at(start, end, corners, shared):
    """Runs ``[a, b]`` and their cluster number after cutting the clusters at ``corners``.

    ``shared``: the corner point ends one run and starts the next.
    """
    a = np.sort(np.concatenate((start, corners + (0 if shared else 1))))
    b = np.sort(np.concatenate((corners, end)))
    owner = np.searchsorted(start, a, side="right") - 1
    return a, b, owner


@kernel
def refine_cuts(cost, a, b, owner):
    """Move each cut (end ``b[k]`` / start ``a[k+1]``) by one position where that fits better.

    Every cut is judged against the original neighbours; two cuts moving
    towards each other that would leave a run of one point both stay put.
    """
    m = a.shape[0]
    new_a, new_b = a.copy(), b.copy()
    for k in range(m - 1):
        if owner[k] != owner[k + 1]:
            continue
        best_cost, best_shift = math.inf, 0
        for shift in (0, -1, 1):
            cut = b[k] + shift
            if cut - a[k] < 1 or b[k + 1] - cut - 1 < 1:
                continue
            total = run_cost(cost, a[k], cut) + run_cost(cost, cut + 1, b[k + 1])
            if total < best_cost - 1e-15:  # NaN never wins
                best_cost, best_shift = total, shift
        new_b[k] = b[k] + best_shift
        new_a[k + 1] = new_b[k] + 1
    too_short = new_b - new_a < 1
    for k in range(m - 1):
        if owner[k] == owner[k + 1] and (too_short[k] or too_short[k + 1]):
            new_b[k], new_a[k + 1] = b[k], a[k + 1]
    return new_a, new_b
