"""Refining a segmentation: merge collinear neighbours, split on a residual bound.

``merge_collinear`` joins two neighbouring segments of one cluster when the
joined fit explains the points as well, by the same criterion the sweep uses:
``(SSE_joined - SSE_1 - SSE_2) / sigma^2 < penalty * ln(n)``. It undoes cuts at
noise peaks that a single global threshold lets through.

``split_by_residual`` enforces a hard bound: while a point of a segment lies
farther than ``max_residual`` from its line, the segment is cut at its worst
point (as iterative end-point fit does) and that point is left out of both parts.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import jit
from scanlines.steps.fit import FIT_CODES, Moments, RunCost, fit_run, run_cost

__all__ = ["merge_collinear", "split_by_residual"]


@jit
def merge_runs(fit, table, ox, oy, inv_r2, a, b, cluster, segment_cost: float):
    """Kernel of :func:`merge_collinear` (``segment_cost`` in the cost's units).

    The costs of the parts and of each joined pair are kept between rounds;
    a merge changes only the pairs next to it.
    """
    a, b, cluster = a.copy(), b.copy(), cluster.copy()
    m = a.shape[0]
    part = np.empty(m)
    for k in range(m):
        part[k] = run_cost(fit, table, ox, oy, inv_r2, a[k], b[k])
    joined = np.full(max(m - 1, 0), math.nan)
    for k in range(m - 1):
        if cluster[k] == cluster[k + 1]:
            joined[k] = run_cost(fit, table, ox, oy, inv_r2, a[k], b[k + 1])
    while m >= 2:
        best, best_change = -1, math.inf
        for k in range(m - 1):
            change = joined[k] - part[k] - part[k + 1] - segment_cost
            if change < best_change:  # NaN (other cluster, no line) never wins
                best, best_change = k, change
        if best < 0 or not best_change < 0.0:
            break
        b[best] = b[best + 1]
        part[best] = joined[best]
        a[best + 1 : m - 1] = a[best + 2 : m]
        b[best + 1 : m - 1] = b[best + 2 : m]
        cluster[best + 1 : m - 1] = cluster[best + 2 : m]
        part[best + 1 : m - 1] = part[best + 2 : m]
        joined[best : m - 2] = joined[best + 1 : m - 1]
        m -= 1
        for k in (best - 1, best):
            if 0 <= k < m - 1:
                same = cluster[k] == cluster[k + 1]
                cost = run_cost(fit, table, ox, oy, inv_r2, a[k], b[k + 1])
                joined[k] = cost if same else math.nan
    return a[:m], b[:m], cluster[:m]


def merge_collinear(
    cost: RunCost,
    a: np.ndarray,
    b: np.ndarray,
    cluster: np.ndarray,
    *,
    sigma: float,
    penalty: float,
    n_points: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Greedily merge the neighbour pair that lowers the criterion most, until none does."""
    ox, oy = cost.moments.origin
    return merge_runs(
        FIT_CODES[cost.fit],
        cost.moments.table,
        ox,
        oy,
        cost.inv_r2,
        np.asarray(a, dtype=np.int64),
        np.asarray(b, dtype=np.int64),
        np.asarray(cluster, dtype=np.int64),
        penalty * math.log(max(n_points, 2)) * sigma * sigma,
    )


@jit
def split_runs(x, y, fit, table, ox, oy, a, b, cluster, max_residual: float, min_points: int):
    """Kernel of :func:`split_by_residual`: each run is split recursively, left part first."""
    out_a = np.empty(x.shape[0] + 1, dtype=np.int64)
    out_b = np.empty(x.shape[0] + 1, dtype=np.int64)
    out_cluster = np.empty(x.shape[0] + 1, dtype=np.int64)
    count = 0
    stack_a = np.empty(x.shape[0] + 1, dtype=np.int64)
    stack_b = np.empty(x.shape[0] + 1, dtype=np.int64)
    for k in range(a.shape[0]):
        top = 0
        stack_a[0], stack_b[0] = a[k], b[k]
        top = 1
        while top:
            top -= 1
            lo, hi = stack_a[top], stack_b[top]
            if hi - lo + 1 < max(min_points, 1):
                continue
            rho, alpha, _ = fit_run(fit, table, ox, oy, lo, hi)
            c, s = math.cos(alpha), math.sin(alpha)
            worst, worst_at = -1.0, -1
            for p in range(lo, hi + 1):
                distance = abs(x[p] * c + y[p] * s - rho)
                if distance > worst:  # NaN (no line) never counts
                    worst, worst_at = distance, p
            if worst > max_residual:
                stack_a[top], stack_b[top] = worst_at + 1, hi  # right part after the left
                stack_a[top + 1], stack_b[top + 1] = lo, worst_at - 1
                top += 2
                continue
            out_a[count], out_b[count], out_cluster[count] = lo, hi, cluster[k]
            count += 1
    return out_a[:count], out_b[:count], out_cluster[:count]


def split_by_residual(
    x: np.ndarray,
    y: np.ndarray,
    moments: Moments,
    fit: str,
    a: np.ndarray,
    b: np.ndarray,
    cluster: np.ndarray,
    *,
    max_residual: float,
    min_points: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cut segments at their worst point until every point is within ``max_residual``.

    Parts shorter than ``min_points`` are dropped. Terminates because every cut
    removes a point.
    """
    ox, oy = moments.origin
    return split_runs(
        np.asarray(x, dtype=np.float64),
        np.asarray(y, dtype=np.float64),
        FIT_CODES[fit],
        moments.table,
        ox,
        oy,
        np.asarray(a, dtype=np.int64),
        np.asarray(b, dtype=np.int64),
        np.asarray(cluster, dtype=np.int64),
        float(max_residual),
        int(min_points),
    )
