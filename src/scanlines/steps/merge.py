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

from scanlines.steps.fit import Moments, RunCost, fit_runs, point_residuals, run_labels

__all__ = ["merge_collinear", "split_by_residual"]


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
    a, b, cluster = a.copy(), b.copy(), cluster.copy()
    segment_cost = penalty * math.log(max(n_points, 2)) * sigma * sigma
    while a.size >= 2:
        pair = np.flatnonzero(cluster[:-1] == cluster[1:])
        if pair.size == 0:
            break
        joined = cost(a[pair], b[pair + 1])
        parts = cost(a, b)
        change = joined - parts[pair] - parts[pair + 1] - segment_cost
        change = np.where(np.isnan(change), np.inf, change)
        best = int(np.argmin(change))
        if not change[best] < 0.0:
            break
        k = int(pair[best])
        b[k] = b[k + 1]
        a, b, cluster = np.delete(a, k + 1), np.delete(b, k + 1), np.delete(cluster, k + 1)
    return a, b, cluster


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
    while a.size:
        lines = fit_runs(fit, moments, a, b)
        position, run = run_labels(a, b, x.shape[0])
        distance = np.abs(point_residuals(x, y, lines.rho, lines.alpha, position, run))
        distance = np.where(np.isnan(distance), -np.inf, distance)  # no line (paper fit): no test
        worst_value = np.full(a.size, -1.0)
        np.maximum.at(worst_value, run, distance)
        bad = np.flatnonzero(worst_value > max_residual)
        if bad.size == 0:
            break
        is_worst = (distance == worst_value[run]) & np.isin(run, bad)
        first_worst = np.full(a.size, -1, dtype=np.intp)
        hit = np.flatnonzero(is_worst)
        # the first worst point of each bad run (positions within a run ascend)
        first_worst[run[hit[::-1]]] = position[hit[::-1]]
        w = first_worst[bad]
        new_a = np.concatenate((np.delete(a, bad), a[bad], w + 1))
        new_b = np.concatenate((np.delete(b, bad), w - 1, b[bad]))
        new_cluster = np.concatenate((np.delete(cluster, bad), cluster[bad], cluster[bad]))
        keep = new_b - new_a + 1 >= max(min_points, 1)
        order = np.argsort(new_a[keep], kind="stable")
        a, b, cluster = new_a[keep][order], new_b[keep][order], new_cluster[keep][order]
    return a, b, cluster
