"""Line segments as the exact penalised-likelihood partition of a scan's returns.

The method solves one problem per scan: cut the returns, in beam order, into runs that are
line segments and single returns left out as clutter, so that the total cost

    sum over segments of  (chi2 / 2 + penalty)  +  clutter_cost x (returns left out)

is smallest. A segment's ``chi2`` is its weighted total-least-squares residual: each return
``p`` weighs ``1 / (sigma(r_p)^2 + model_error^2)``, with ``sigma(r)`` the range noise
measured from the data (the sensor profile's noise line, else the scan's own,
:mod:`scanlines.steps.noise`) and ``model_error`` the flatness of real walls. The costs are
negative log-likelihoods in nats, so ``penalty`` and ``clutter_cost`` are nats too: a segment
is cut where the fit improves by more than the price of one more segment, a return is left
out where its residual costs more than ``clutter_cost`` (about ``sqrt(2 clutter_cost)``
sigmas). Runs of two or more missing beams end a cluster, and no segment spans them.

The optimum is found exactly by dynamic programming over the positions, with every
segment's cost in O(1) from prefix sums of the weighted moments, and pruned as PELT [1]_
does: a start ``s`` whose best cost to ``t`` already exceeds the best cost of ``t`` itself
can never start the last segment of a later optimum (a segment's chi2 only grows when it
is cut in two), so it is dropped once every later segment from ``t`` would be long enough.

Events are read off the partition. Between two neighbouring pieces (segments or left-out
returns) of one cluster a *breakpoint* is reported at the last return of the first piece
when the two facing returns are farther apart than a surface seen at up to 80 deg of
incidence can put them (Borges and Aldon's bound [2]_) plus three sigmas of their
difference. Two neighbouring segments meet at a *corner* when their lines turn by more
than three standard deviations of the turn (the direction variance of a weighted fit is
``1 / lambda_max`` of its scatter) and intersect within the facing returns' spacing plus
three noise sigmas of both facing returns; the corner is the facing return nearer the
intersection.

With ``max_rho_sigma`` (preset ``"repeatable"``) only well-determined lines are kept:
segments whose ``rho`` standard deviation, in the covariance reported with them, exceeds
the bound are dropped, which removes lines through sparse returns at grazing incidence and
short lines far from the foot of their normal.

References
----------
.. [1] R. Killick, P. Fearnhead and I. A. Eckley, "Optimal detection of changepoints with
   a linear computational cost", J. American Statistical Association 107, 1590-1598, 2012.
.. [2] G. A. Borges and M.-J. Aldon, "Line extraction in 2D range images for mobile
   robotics", J. Intelligent and Robotic Systems 40, 267-297, 2004.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from scanlines._jit import kernel, scan_kernel
from scanlines.methods.base import CompiledMethod
from scanlines.methods.partition_settings import (
    CUT_SIGMAS,
    EVENT_SIGMAS,
    GRAZING_ANGLE,
    PARAMETERS,
    PRESETS,
)
from scanlines.params import Param
from scanlines.steps.assemble import assemble, empty_result
from scanlines.steps.fit import TLS, prefix_moments
from scanlines.steps.noise import NoiseLine, noise_at, resolve_noise
from scanlines.steps.returns import MAX_BRIDGED_GAP, Returns, beam_gaps, rotated, valid_returns
from scanlines.steps.stack import add_row, new_table

__all__ = ["Partition"]


class Partition(CompiledMethod):
    """The penalised-likelihood partition of each scan into line segments (module
    docstring)."""

    name = "partition"
    parameters: ClassVar[dict[str, Param]] = PARAMETERS
    presets: ClassVar[dict[str, dict[str, Any]]] = PRESETS

    @staticmethod
    def kernel(*arguments):
        return partition_stack(*arguments)


# --------------------------------------------------------------------------- the kernel


@kernel
def partition_stack(stack, valid, cos, sin, step, full_circle, angle_min, noise, settings):
    """:func:`partition_scan` of each row of ``stack``, as one flat table."""
    table = new_table(stack.shape[0])
    for row in range(stack.shape[0]):
        result = partition_scan(
            stack[row], valid[row], cos, sin, step, full_circle, angle_min, noise, settings
        )
        table = add_row(table, row, result)
    return table


@scan_kernel
def partition_scan(ranges, valid, cos, sin, step, full_circle, angle_min, noise, settings):
    """The whole method on one scan: the result arrays (see :class:`CompiledMethod`)."""
    s = settings[0]
    n_beams = ranges.shape[0]
    returns = valid_returns(ranges, valid, cos, sin)
    none = np.zeros(0, dtype=np.int64)
    if returns.index.shape[0] == 0:
        return empty_result(none, none)
    gap = beam_gaps(returns.index, n_beams)
    if s.noise_sigma == s.noise_sigma:
        noise = NoiseLine(s.noise_sigma, 0.0)
    noise = resolve_noise(noise, returns, gap)
    ring = False
    if full_circle:
        returns, ring = seam_at_widest_gap(returns, gap, n_beams)
    sigma = np.empty(returns.r.shape[0])
    for p in range(sigma.shape[0]):
        sigma[p] = noise_at(noise, returns.r[p])
    a, b, held, sums, gap = best_partition(returns, sigma, n_beams, step, s)
    if ring and a.shape[0] > 1:
        # A closed ring: cut it where the first optimum had a boundary, and solve again.
        returns = rotated(returns, b[0] + 1)
        sigma = np.concatenate((sigma[b[0] + 1 :], sigma[: b[0] + 1]))
        a, b, held, sums, gap = best_partition(returns, sigma, n_beams, step, s)
    breakpoints, corners = partition_events(
        returns, sums, sigma, a, b, gap, step, (full_circle, ring, n_beams)
    )
    outliers = returns.index[~held]
    keep = kept_runs(returns, held, a, b, s.min_points, s.min_length)
    returns, a, b = without_left_out(returns, held, a[keep], b[keep])
    sigma = sigma[held]
    if s.range_sigma == s.range_sigma:
        sigma = np.full(returns.r.shape[0], s.range_sigma)
    events = (breakpoints, corners, outliers)
    moments = prefix_moments(returns.x, returns.y)
    result = assemble(
        returns, np.int64(TLS), moments, a, b, angle_min, sigma, events, (n_beams, ring)
    )
    return well_determined(result, s.max_rho_sigma)


@kernel
def seam_at_widest_gap(returns, gap, n_beams):
    """A full circle's returns rotated to start after their widest gap, and whether they
    close into a ring (no gap of two or more missing beams anywhere)."""
    n = returns.index.shape[0]
    if n < 2:
        return returns, False
    widest = 0
    for p in range(gap.shape[0]):
        if gap[p] > gap[widest]:
            widest = p
    closing = (returns.index[0] - returns.index[n - 1]) % n_beams  # last return to first
    if closing >= gap[widest]:
        return returns, closing <= MAX_BRIDGED_GAP
    return rotated(returns, widest + 1), gap[widest] <= MAX_BRIDGED_GAP


LOOK_BACK = 256
"""Most returns the last segment may reach back over in the partition: the bound that keeps
the work linear along long walls, where no start is ever dominated. A wall of more returns
is cut there and joined again by :func:`joined_runs`, on the same objective."""

ROUNDS = 3
"""Most rounds of partition and outlier choice (:func:`best_partition`)."""


@kernel
def best_partition(returns, sigma, n_beams, step, s):
    """Runs ``[a, b]`` and the returns ``held`` in a line fit, by rounds of the exact
    partition and the choice of each segment's outliers (a return whose residual costs
    more than ``clutter_cost`` is left out without cutting its segment); each round lowers
    the one objective, and a round that changes nothing ends them. Also the final sums
    and beam gaps."""
    index, r, x, y = returns
    gap = beam_gaps(index, n_beams)
    opens = np.empty(index.shape[0], dtype=np.bool_)
    opens[0] = True
    for p in range(1, index.shape[0]):
        bridged = gap[p - 1] <= MAX_BRIDGED_GAP
        step_ok = continuous(x, y, r, p - 1, p, gap[p - 1], step, sigma, CUT_SIGMAS)
        opens[p] = not (bridged and step_ok)
    held = np.ones(index.shape[0], dtype=np.bool_)
    for _ in range(ROUNDS):
        sums = weighted_sums(x, y, sigma, s.model_error, held)
        a, b = optimal_runs(sums, opens, s.penalty, s.clutter_cost, s.min_points)
        a, b = joined_runs(sums, opens, a, b, s.penalty, s.clutter_cost)
        if not choose_outliers(x, y, sums, sigma, s.model_error, a, b, s.clutter_cost, held):
            break
    sums = weighted_sums(x, y, sigma, s.model_error, held)
    a, b = trimmed_runs(held, a, b)
    for p in range(index.shape[0]):  # returns outside the runs are outliers too
        held[p] = False
    for k in range(a.shape[0]):
        for p in range(a[k], b[k] + 1):
            held[p] = True
    held &= np.asarray(inside_fit(x, y, sums, sigma, s.model_error, a, b, s.clutter_cost))
    a, b = trimmed_runs(held, a, b)  # a run's end may have left its fit
    return a, b, held, sums, gap


@kernel
def inside_fit(x, y, sums, sigma, model_error, a, b, clutter_cost):
    """Whether each return lies in its run's fit (residual cost at most ``clutter_cost``;
    returns outside the runs: True)."""
    out = np.ones(x.shape[0], dtype=np.bool_)
    floor = model_error * model_error
    for k in range(a.shape[0]):
        rho, alpha, _, _ = line_of(sums, a[k], b[k], x[0], y[0])
        c, si = math.cos(alpha), math.sin(alpha)
        for p in range(a[k], b[k] + 1):
            off = x[p] * c + y[p] * si - rho
            out[p] = 0.5 * off * off / (sigma[p] * sigma[p] + floor) <= clutter_cost
    return out


@kernel
def choose_outliers(x, y, sums, sigma, model_error, a, b, clutter_cost, held):
    """Set ``held`` to the returns that fit their run's line (others, all True); returns
    whether anything changed."""
    fits = inside_fit(x, y, sums, sigma, model_error, a, b, clutter_cost)
    changed = False
    for p in range(held.shape[0]):
        if fits[p] != held[p]:
            held[p] = fits[p]
            changed = True
    return changed


@kernel
def trimmed_runs(held, a, b):
    """Runs ``[a, b]`` that start and end at returns held in their fit."""
    a, b = a.copy(), b.copy()
    for k in range(a.shape[0]):
        while a[k] < b[k] and not held[a[k]]:
            a[k] += 1
        while b[k] > a[k] and not held[b[k]]:
            b[k] -= 1
    return a, b


@kernel
def without_left_out(returns, held, a, b):
    """The returns held in a fit, and runs ``[a, b]`` renumbered to them."""
    position = np.cumsum(held) - 1
    index, r, x, y = returns
    keep = np.flatnonzero(held)
    return Returns(index[keep], r[keep], x[keep], y[keep]), position[a], position[b]


@kernel
def weighted_sums(x, y, sigma, model_error, held):
    """Prefix sums of the weighted moments ``w, wx, wy, wxx, wxy, wyy`` and the count of
    ``held`` returns (rows 0..n), each held return weighing ``1 / (sigma^2 +
    model_error^2)``, others nothing; coordinates from the first return, which keeps the
    sums small."""
    n = x.shape[0]
    out = np.zeros((n + 1, 7))
    floor = model_error * model_error
    for p in range(n):
        w = 1.0 / (sigma[p] * sigma[p] + floor) if held[p] else 0.0
        u, v = x[p] - x[0], y[p] - y[0]
        out[p + 1, 0] = out[p, 0] + w
        out[p + 1, 1] = out[p, 1] + w * u
        out[p + 1, 2] = out[p, 2] + w * v
        out[p + 1, 3] = out[p, 3] + w * u * u
        out[p + 1, 4] = out[p, 4] + w * u * v
        out[p + 1, 5] = out[p, 5] + w * v * v
        out[p + 1, 6] = out[p, 6] + (1.0 if held[p] else 0.0)
    return out


@kernel
def scatter(sums, a, b):
    """Weight, centroid and weighted scatter ``(W, mx, my, sxx, sxy, syy)`` of positions
    ``a..b`` (centroid relative to the first return of the scan)."""
    w = sums[b + 1, 0] - sums[a, 0]
    mx = (sums[b + 1, 1] - sums[a, 1]) / w
    my = (sums[b + 1, 2] - sums[a, 2]) / w
    sxx = sums[b + 1, 3] - sums[a, 3] - w * mx * mx
    sxy = sums[b + 1, 4] - sums[a, 4] - w * mx * my
    syy = sums[b + 1, 5] - sums[a, 5] - w * my * my
    return w, mx, my, sxx, sxy, syy


@kernel
def eigenvalues(sxx, sxy, syy):
    """The smaller and larger eigenvalue of the scatter ``[[sxx, sxy], [sxy, syy]]``."""
    half = 0.5 * (sxx + syy)
    spread = math.sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy)
    return max(half - spread, 0.0), half + spread


@kernel
def optimal_runs(sums, opens, penalty, clutter_cost, min_points):
    """The optimal partition (module docstring): runs ``[a, b]`` of positions, in order.

    ``best[t]`` is the least cost of the first ``t`` positions, ``start[t]`` the first
    position of the segment that ends the optimum there (``-1``: position ``t - 1`` is
    left out). ``expires[s]``: once a start is dominated at ``t`` it is kept only until
    ``t + min_points``, the first end a segment from ``t`` may have.
    """
    n = sums.shape[0] - 1
    best = np.empty(n + 1)
    start = np.empty(n + 1, dtype=np.int64)
    candidates = np.empty(n + 1, dtype=np.int64)
    expires = np.full(n + 1, n + 1, dtype=np.int64)
    cost = np.empty(n + 1)  # each candidate's cost to t, before the segment's penalty
    best[0] = 0.0
    count = 0
    for t in range(1, n + 1):
        if opens[t - 1]:
            count = 0  # position t - 1 opens a cluster: no segment reaches back past it
        candidates[count] = t - 1
        count += 1
        best[t] = best[t - 1] + clutter_cost
        start[t] = -1
        kept = 0
        for c in range(count):
            s = candidates[c]
            if expires[s] <= t or t - s > LOOK_BACK:
                continue
            candidates[kept] = s
            cost[kept] = math.inf
            held = sums[t, 6] - sums[s, 6]
            if held >= min_points:
                _, _, _, sxx, sxy, syy = scatter(sums, s, t - 1)
                cost[kept] = best[s] + 0.5 * eigenvalues(sxx, sxy, syy)[0]
                cost[kept] += clutter_cost * (t - s - held)
                if cost[kept] + penalty < best[t]:
                    best[t] = cost[kept] + penalty
                    start[t] = s
            kept += 1
        count = kept
        for c in range(count):  # prune the starts that t dominates (PELT)
            if cost[c] >= best[t] and cost[c] < math.inf and expires[candidates[c]] > n:
                expires[candidates[c]] = t + min_points
    a = np.empty(n, dtype=np.int64)
    b = np.empty(n, dtype=np.int64)
    m = 0
    t = n
    while t > 0:
        if start[t] < 0:
            t -= 1
            continue
        a[m], b[m] = start[t], t - 1
        m += 1
        t = start[t]
    return a[:m][::-1].copy(), b[:m][::-1].copy()


@kernel
def run_cost(sums, a, b, penalty, clutter_cost):
    """The objective's share of one segment ``a..b``: its chi2 / 2, its left-out returns
    and its penalty."""
    held = sums[b + 1, 6] - sums[a, 6]
    _, _, _, sxx, sxy, syy = scatter(sums, a, b)
    return 0.5 * eigenvalues(sxx, sxy, syy)[0] + clutter_cost * (b - a + 1 - held) + penalty


@kernel
def joined_runs(sums, opens, a, b, penalty, clutter_cost):
    """Runs ``[a, b]`` with each neighbour joined to the run before it where one segment
    costs less than the two (the cuts :data:`LOOK_BACK` forces on long walls)."""
    if a.shape[0] < 2:
        return a, b
    out_a, out_b = a.copy(), b.copy()
    m = 0
    for k in range(1, a.shape[0]):
        touching = out_b[m] + 1 == a[k] and not opens[a[k]]
        if touching and run_cost(sums, out_a[m], b[k], penalty, clutter_cost) <= (
            run_cost(sums, out_a[m], out_b[m], penalty, clutter_cost)
            + run_cost(sums, a[k], b[k], penalty, clutter_cost)
        ):
            out_b[m] = b[k]
        else:
            m += 1
            out_a[m], out_b[m] = a[k], b[k]
    return out_a[: m + 1].copy(), out_b[: m + 1].copy()


@kernel
def line_of(sums, a, b, x0, y0):
    """Hesse line ``(rho, alpha)`` of the weighted fit of positions ``a..b`` (in the
    returns' frame, ``x0, y0`` the first return), its direction variance and its weight."""
    w, mx, my, sxx, sxy, syy = scatter(sums, a, b)
    alpha = 0.5 * math.atan2(-2.0 * sxy, syy - sxx)
    rho = (mx + x0) * math.cos(alpha) + (my + y0) * math.sin(alpha)
    if rho < 0.0:
        rho, alpha = -rho, alpha + math.pi
    large = eigenvalues(sxx, sxy, syy)[1]
    return rho, alpha, 1.0 / large if large > 0.0 else math.inf, w


@kernel
def continuous(x, y, r, p, q, beams, step, sigma, sigmas):
    """Whether returns ``p`` and ``q`` (``beams`` apart) may lie on one surface."""
    turn = beams * step
    if turn >= GRAZING_ANGLE:
        return False
    reach = min(r[p], r[q]) * math.sin(turn) / math.sin(GRAZING_ANGLE - turn)
    apart = math.hypot(x[q] - x[p], y[q] - y[p])
    spread = sigmas * math.sqrt(sigma[p] * sigma[p] + sigma[q] * sigma[q])
    return apart <= reach + spread


@kernel
def partition_events(returns, sums, sigma, a, b, gap, step, shape):
    """Breakpoints and corners (beams) between the pieces of the partition (module
    docstring). Pieces are the runs ``[a, b]`` and the returns between them; ``shape`` is
    ``(full_circle, ring, n_beams)``: a full circle that is no ring starts after a gap."""
    index, r, x, y = returns
    full_circle, ring, n_beams = shape
    n = index.shape[0]
    breakpoints = np.empty(n, dtype=np.int64)
    corners = np.empty(max(a.shape[0], 1), dtype=np.int64)
    n_breaks = n_corners = 0
    owner = np.full(n, -1, dtype=np.int64)
    for k in range(a.shape[0]):
        owner[a[k] : b[k] + 1] = k
    for p in range(n - 1 if not ring else n):
        q = (p + 1) % n
        if owner[p] >= 0 and owner[p] == owner[q]:
            continue
        beams = gap[p] if p < n - 1 else (index[0] - index[n - 1]) % n_beams
        across_gap = p < n - 1 and gap[p] > MAX_BRIDGED_GAP
        if across_gap or not continuous(x, y, r, p, q, beams, step, sigma, EVENT_SIGMAS):
            breakpoints[n_breaks] = index[p]
            n_breaks += 1
        elif owner[p] >= 0 and owner[q] >= 0:
            at = corner_between(x, y, sums, sigma, a, b, owner[p], owner[q])
            if at >= 0:
                corners[n_corners] = index[at]
                n_corners += 1
    if full_circle and not ring:
        breakpoints[n_breaks] = index[n - 1]
        n_breaks += 1
    return np.sort(breakpoints[:n_breaks]), corners[:n_corners].copy()


@kernel
def corner_between(x, y, sums, sigma, a, b, i, j):
    """The position of the corner where segments ``i`` and ``j`` (neighbours) meet, or -1:
    their turn is resolved and their lines meet near the facing returns."""
    rho_i, alpha_i, var_i, _ = line_of(sums, a[i], b[i], x[0], y[0])
    rho_j, alpha_j, var_j, _ = line_of(sums, a[j], b[j], x[0], y[0])
    turn = alpha_j - alpha_i
    turn -= math.pi * math.floor(turn / math.pi + 0.5)  # undirected: in [-pi/2, pi/2)
    if abs(turn) <= EVENT_SIGMAS * math.sqrt(var_i + var_j):
        return -1
    det = math.sin(alpha_j - alpha_i)
    cx = (rho_i * math.sin(alpha_j) - rho_j * math.sin(alpha_i)) / det
    cy = (rho_j * math.cos(alpha_i) - rho_i * math.cos(alpha_j)) / det
    end, begin = b[i], a[j]
    spacing = math.hypot(x[begin] - x[end], y[begin] - y[end])
    reach = spacing + EVENT_SIGMAS * max(sigma[end], sigma[begin])
    to_end = math.hypot(cx - x[end], cy - y[end])
    to_begin = math.hypot(cx - x[begin], cy - y[begin])
    if to_end > reach or to_begin > reach:
        return -1
    return end if to_end <= to_begin else begin


@kernel
def left_out(index, a, b):
    """Beams of the returns that no run holds."""
    held = np.zeros(index.shape[0], dtype=np.bool_)
    for k in range(a.shape[0]):
        held[a[k] : b[k] + 1] = True
    return index[~held]


@kernel
def kept_runs(returns, held, a, b, min_points, min_length):
    """Which runs hold at least ``min_points`` returns in their fit and are at least
    ``min_length`` long."""
    x, y = returns.x, returns.y
    keep = np.empty(a.shape[0], dtype=np.bool_)
    for k in range(a.shape[0]):
        count = np.sum(held[a[k] : b[k] + 1])
        length = math.hypot(x[b[k]] - x[a[k]], y[b[k]] - y[a[k]])
        keep[k] = count >= min_points and length >= min_length
    return keep


@kernel
def well_determined(result, max_rho_sigma):
    """:func:`~scanlines.steps.assemble.assemble`'s result without the segments whose
    reported ``rho`` standard deviation exceeds ``max_rho_sigma``."""
    first, last, n_points, lines, covariances, breakpoints, corners, outliers, ends = result
    keep = np.empty(first.shape[0], dtype=np.bool_)
    for k in range(first.shape[0]):
        keep[k] = covariances[k, 0, 0] <= max_rho_sigma * max_rho_sigma
    return (
        first[keep], last[keep], n_points[keep], lines[keep], covariances[keep],
        breakpoints, corners, outliers, ends[keep],
    )  # fmt: skip
