"""The loop the consensus methods (RANSAC, Hough) share: propose a line, refit, cut, remove.

Repeatedly, per cluster: the method's line finder proposes a line through the free
points; its inliers (within ``inlier_distance``) are refitted by total least squares
and collected again; the consensus set is cut into runs contiguous in beam order
(:func:`inlier_runs`); runs of at least ``min_points`` inliers become segments and
their points leave the set. When no run is long enough the whole consensus set
leaves instead, so every round removes points. A cluster's search stops when fewer
than ``min_points`` free points remain, a line has fewer inliers, or ``max_misses``
lines in a row gave no segment (what is left is clutter: on a scan of random ranges
the search would otherwise take one line of clutter at a time, at a cost of the whole
scan each, which grows as the square of the beams).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from scanlines.methods.base import NO_CLUSTERING, ClusteredMethod
from scanlines.params import Param, choice, coded, integer
from scanlines.steps.breakpoints import NO_RULE, RULE_CODES, RULES
from scanlines.steps.fit import prefix_moments, tls_run
from scanlines.steps.returns import MAX_BRIDGED_GAP, Returns

__all__ = [
    "BRIDGE_RETURNS",
    "MAX_MISSES",
    "WHOLE_SCAN",
    "ConsensusMethod",
    "LineFinder",
    "inlier_runs",
]

BRIDGE_RETURNS = 1
"""Most returns between two consecutive inliers of one consensus run (:func:`inlier_runs`):
one return off the line (a noise peak, a spurious echo) does not cut a wall."""

MAX_MISSES = Param(
    20,
    integer(1, 1_000_000),
    "stop a cluster's search after this many lines in a row gave no segment",
)

WHOLE_SCAN = Param(
    NO_CLUSTERING,
    choice(NO_CLUSTERING, *RULES),
    "clustering rule: none (whole scan) | " + " | ".join(RULES),
    (coded({NO_CLUSTERING: NO_RULE, **RULE_CODES}),),
)
"""The ``breakpoints`` parameter of a consensus method: the whole scan by default."""

_EMPTY = np.zeros(0, dtype=np.int64)


class LineFinder(Protocol):
    """The search of one consensus method for its next line in one cluster."""

    def best_line(self, free: np.ndarray) -> tuple[float, float] | None:
        """``(rho, alpha)`` of the best line through the ``free`` positions, or ``None``."""
        ...

    def remove(self, positions: np.ndarray) -> None:
        """Forget the points at ``positions`` (they belong to a segment now)."""
        ...


class ConsensusMethod(ClusteredMethod):
    """A consensus method; a subclass implements :meth:`line_finder`."""

    def line_finder(self, returns: Returns, member: np.ndarray, search: Any) -> LineFinder:
        """The line search over the points ``member`` of one cluster; ``search`` is what
        :meth:`new_search` made for this scan."""
        raise NotImplementedError

    def new_search(self) -> Any:
        """State shared by the clusters of one scan (RANSAC: its random generator)."""
        return None

    def find_runs(self, returns, gap, start, end):
        search = self.new_search()
        found: list[tuple[np.ndarray, ...]] = []
        min_points = self.params["min_points"]
        for c, (first, last) in enumerate(zip(start, end, strict=True)):
            if last - first + 1 < min_points:
                continue
            member = np.zeros(returns.index.shape[0], dtype=bool)
            member[first : last + 1] = True
            finder = self.line_finder(returns, member, search)
            a, b, bridged = self._segments(returns, gap, member, finder)
            found.append((a, b, np.full(a.size, c, dtype=np.int64), bridged))
        if not found:
            return _EMPTY, _EMPTY, _EMPTY, _EMPTY
        a, b, group, bridged = (np.concatenate(part) for part in zip(*found, strict=True))
        order = np.argsort(a, kind="stable")
        return a[order], b[order], group[order], bridged

    def _segments(self, returns, gap, member, finder):
        """Segments ``a, b`` (unordered) of one cluster and the positions bridged inside them."""
        min_points = self.params["min_points"]
        inlier_distance = self.params["inlier_distance"]
        free = member.copy()
        runs_a, runs_b, bridged_all = [], [], []
        misses = 0
        while np.count_nonzero(free) >= min_points and misses < self.params["max_misses"]:
            proposal = finder.best_line(free)
            if proposal is None:
                break
            inlier = _refitted_inliers(returns, free, proposal, inlier_distance)
            if np.count_nonzero(inlier) < min_points:
                break
            a, b, bridged = inlier_runs(returns, gap, inlier, free, self.params["max_gap"])
            long_enough = _run_inlier_counts(inlier, a, b) >= min_points
            taken = _covered(returns.index.shape[0], a[long_enough], b[long_enough])
            misses = 0 if long_enough.any() else misses + 1
            if not long_enough.any():
                taken = inlier
            runs_a.append(a[long_enough])
            runs_b.append(b[long_enough])
            bridged_all.append(bridged[taken[bridged]])
            free &= ~taken
            finder.remove(np.flatnonzero(taken))
        if not runs_a:
            return _EMPTY, _EMPTY, _EMPTY
        return tuple(
            np.concatenate(part).astype(np.int64) for part in (runs_a, runs_b, bridged_all)
        )


def inlier_runs(
    returns: Returns, gap: np.ndarray, inlier: np.ndarray, free: np.ndarray, max_gap: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of a consensus set that are contiguous in beam order.

    Consecutive inliers stay in one run when at most :data:`BRIDGE_RETURNS` returns
    lie between them (returns not taken by an earlier segment: ``free``), no two or
    more consecutive beams are missing between them (``gap``) and they are at most
    ``max_gap`` metres apart.

    Returns ``a, b`` (first and last inlier of each run) and the positions inside the
    runs that are not inliers (to be dropped as outliers).
    """
    found = np.flatnonzero(inlier)
    if found.size == 0:
        return _EMPTY, _EMPTY, _EMPTY
    before, after = found[:-1], found[1:]
    skipped = after - before - 1
    taken = np.r_[0, np.cumsum(~free)]
    wide = np.r_[0, np.cumsum(gap > MAX_BRIDGED_GAP)]
    x, y = returns.x, returns.y
    distance = np.hypot(x[after] - x[before], y[after] - y[before])
    joined = (
        (skipped <= BRIDGE_RETURNS)
        & (taken[after] - taken[before + 1] == 0)
        & (wide[after] - wide[before] == 0)
        & (distance <= max_gap)
    )
    cut = np.flatnonzero(~joined)
    a = found[np.r_[0, cut + 1]]
    b = found[np.r_[cut, found.size - 1]]
    covered = _covered(returns.index.shape[0], a, b)
    return a, b, np.flatnonzero(covered & ~inlier)


def _refitted_inliers(
    returns: Returns, free: np.ndarray, line: tuple[float, float], inlier_distance: float
) -> np.ndarray:
    """Free points near ``line``, collected again around their own TLS line.

    Falls back to the first set when the refitted line keeps fewer points.
    """
    x, y = returns.x, returns.y
    rho, alpha = line
    first = free & (np.abs(x * math.cos(alpha) + y * math.sin(alpha) - rho) <= inlier_distance)
    chosen = np.flatnonzero(first)
    if chosen.size < 2:
        return first
    rho, alpha, _ = tls_run(prefix_moments(x[chosen], y[chosen]), 0, chosen.size - 1)
    off = np.abs(x * np.cos(alpha) + y * np.sin(alpha) - rho)
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
