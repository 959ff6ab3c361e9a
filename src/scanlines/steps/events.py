"""Events between consecutive segments: corners, and the jumps that become breakpoints.

``segment_events`` is the one rule every comparison method uses. Of two consecutive
segments, with facing end points ``P_e`` (last of the first) and ``P_s`` (first of the
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

``junction_events`` is the adaptive method's own rule between the segments of one
cluster: the corner beam nearer the lines' intersection, or a breakpoint where the
lines do not meet near their facing ends, or no event where their turn is within the
noise of their directions.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import kernel
from scanlines.extraction import END_KINDS
from scanlines.params import Param, integer, number, radians
from scanlines.steps.fit import TLS, fit_many, fit_run, hesse_difference, line_intersection
from scanlines.steps.returns import MAX_BRIDGED_GAP
from scanlines.steps.split import line_residual

__all__ = [
    "CORNER_REACH",
    "END_KINDS",
    "EVENT_PARAMS",
    "end_kinds",
    "junction_events",
    "segment_events",
    "sorted_distinct",
]

EVENT_PARAMS: dict[str, Param] = {
    "corner_beams": Param(
        2, integer(1, 1000), "corner: most beams between the facing ends of two segments"
    ),
    "corner_distance": Param(
        0.2,
        number(low=0.0, low_open=True),
        "corner: largest distance (m) of a facing end from the two lines' intersection",
    ),
    "corner_angle": Param(
        10.0,
        number(low=0.0, high=90.0),
        "corner: smallest turn between the two lines (deg)",
        (radians(),),
    ),
}
"""Parameters of the shared corner/breakpoint rule (:func:`segment_events`)."""

CORNER_REACH = 2.0
"""A corner's lines meet within this many spacings (plus noise) of the facing ends
(:func:`junction_events`)."""


@kernel
def sorted_distinct(values):
    """The distinct values of an integer array, ascending."""
    ordered = np.sort(values)
    count = min(ordered.shape[0], 1)
    for i in range(1, ordered.shape[0]):
        if ordered[i] != ordered[count - 1]:
            ordered[count] = ordered[i]
            count += 1
    return ordered[:count]


@kernel
def nearest_return(x, y, cx, cy, low, end, start, high, reach, widest):
    """Position nearest ``(cx, cy)`` among ``end - reach .. start + reach`` (within ``low..high``).

    A pair that wraps (the last segment and the first) counts on past the end of
    the sequence. The candidates run on to ``end + reach + widest``, ``widest``
    the most positions between the facing ends of any pair of the scan, and those
    beyond ``high`` count as ``end``. That widening is kept on purpose: it is how
    the first, vectorised implementation searched, every published figure of the
    comparison methods was measured with it, and narrowing the search to the pair's
    own span changes corners (a change of results that belongs with the accuracy
    work, not with a re-housing).
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


@kernel
def segment_events(returns, n_beams, moments, a, b, group, clustered, wrap, bounds):
    """Corners and breakpoints between consecutive segments ``[a, b]`` (module docstring).

    ``clustered``: only segments of one ``group`` can meet and no breakpoints are
    derived (the method's clustering has them); ``wrap``: the last segment is
    followed by the first, across the seam. ``bounds`` is ``(corner_beams,
    corner_distance, corner_angle)`` in beams, metres and radians.

    Returns ``corners, breakpoints``, sorted distinct beams.
    """
    index, _, x, y = returns
    corner_beams, corner_distance, corner_angle = bounds
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
    rho, alpha, _ = fit_many(np.int64(TLS), moments, a, b)
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
            at = nearest_return(x, y, cx, cy, a[i], end, start, b[j], reach, np.int64(widest))
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


CORNER_SIGMAS = 3.0
"""Standard deviations of the turn by which two segments' lines must turn to meet at a
corner (:func:`junction_events`)."""


@kernel
def junction_events(returns, fit, moments, a, b, owner, shared, ring, sigma, turn_sigma):
    """Beams of the corners where two kept segments of one cluster meet, and of jumps.

    A shared corner is its shared point; otherwise the point nearer the two
    lines' intersection among those between the segments. With ``sigma >= 0``,
    two segments whose lines do not meet near their facing ends (farther than
    :data:`CORNER_REACH` times the local spacing plus three ``sigma``) are two
    surfaces at different depths joined by a mixed pixel or a small step: the
    junction is reported as a breakpoint (the last beam of the first segment).
    Given ``turn_sigma`` (the standard deviation of each segment's direction; empty:
    no test), a junction whose lines turn by less than :data:`CORNER_SIGMAS` times the
    standard deviation of the turn is not a corner: the noise hides it (the rule by
    which the simulator's truth makes such a turn don't-care).
    """
    index, _, x, y = returns
    m = a.shape[0]
    corners = np.zeros(m, dtype=np.int64)
    jumps = np.zeros(m, dtype=np.int64)
    n_corners = n_jumps = 0
    for k in range(m):
        right = k + 1
        if right == m:
            if not (ring and m >= 2 and a[0] == 0 and b[-1] == x.shape[0] - 1):
                break
            right = 0
        elif owner[k] != owner[right] or a[right] - b[k] > 2:
            continue
        end, start = b[k], a[right]
        if shared:
            corners[n_corners] = index[start]
            n_corners += 1
            continue
        rho_i, alpha_i, _ = fit_run(fit, moments, a[k], b[k])
        rho_j, alpha_j, _ = fit_run(fit, moments, a[right], b[right])
        cx, cy = line_intersection(rho_i, alpha_i, rho_j, alpha_j)
        before = math.hypot(x[end] - cx, y[end] - cy)
        after = math.hypot(x[start] - cx, y[start] - cy)
        pick = start if after < before else end
        if sigma >= 0.0:
            reach = CORNER_REACH * math.hypot(x[start] - x[end], y[start] - y[end]) + 3.0 * sigma
            if not max(before, after) <= reach:  # NaN (parallel lines) is not a corner
                jumps[n_jumps] = index[end]
                n_jumps += 1
                continue
        if turn_sigma.shape[0] > 0:
            bound = CORNER_SIGMAS * math.sqrt(turn_sigma[k] ** 2 + turn_sigma[right] ** 2)
            _, turn = hesse_difference(rho_i, alpha_i, rho_j, alpha_j)
            if not abs(turn) >= bound:  # the noise hides it (or NaN)
                continue
        corners[n_corners] = index[pick]
        n_corners += 1
    return corners[:n_corners], jumps[:n_jumps]


END_CORNER, END_JUMP, END_OCCLUDED, END_GAP, END_EDGE, END_OPEN = (
    END_KINDS.index(kind) for kind in ("corner", "jump", "occluded", "gap", "edge", "open")
)


@kernel
def near_corner(corners, beam):
    """Whether a corner beam lies within one beam of ``beam`` (``corners`` sorted)."""
    at = np.searchsorted(corners, beam - 1)
    return at < corners.shape[0] and corners[at] <= beam + 1


@kernel
def is_listed(sorted_beams, beam):
    at = np.searchsorted(sorted_beams, beam)
    return at < sorted_beams.shape[0] and sorted_beams[at] == beam


@kernel
def end_kinds(returns, a, b, n_beams, wrap, breakpoints, corners):
    """What ends each run ``[a, b]`` at its start and at its end: codes of :data:`END_KINDS`.

    ``corner``: a corner within one beam. ``gap``: two or more beams without a return
    follow. ``edge``: no return follows (the scan's first or last return; never on a
    closed ring, ``wrap``). ``jump``: a breakpoint, and the return beyond lies farther:
    this surface really ends here. ``occluded``: a breakpoint, and the return beyond
    is nearer: the surface may go on behind it. ``open``: none of these (the method
    stopped the segment on a continuing surface: a curve, clutter, a dropped point).
    ``breakpoints`` and ``corners`` are sorted beam indices.
    """
    index, r = returns.index, returns.r
    n = index.shape[0]
    out = np.empty((a.shape[0], 2), dtype=np.int8)
    for k in range(a.shape[0]):
        for side in range(2):
            p = a[k] if side == 0 else b[k]
            step = -1 if side == 0 else 1
            q = p + step
            if wrap:
                q %= n
            beam = index[p]
            if near_corner(corners, beam):
                out[k, side] = END_CORNER
            elif q < 0 or q >= n or q == p:
                out[k, side] = END_EDGE
            else:
                apart = (index[q] - beam) * step
                if apart < 0:
                    apart += n_beams
                last_before = beam if side == 1 else index[q]
                if apart > MAX_BRIDGED_GAP:
                    out[k, side] = END_GAP
                elif is_listed(breakpoints, last_before):
                    out[k, side] = END_OCCLUDED if r[q] < r[p] else END_JUMP
                else:
                    out[k, side] = END_OPEN
    return out
