"""Loop closure: tracked poses joined into a pose graph, closures found, verified, optimised.

:class:`LoopCloser` takes each tracked scan in log order (:meth:`LoopCloser.add`: its pose
and the pose's covariance, from whatever tracker made them, and the scan, or ``None`` for a
scan that gives no evidence, a held-out one). The graph (:mod:`scanlines.map.posegraph`)
has one pose per scan and a *tracking edge* between consecutive scans: their tracked
relative pose, with the later scan's covariance, floored at ``edge_floor`` metres and
``edge_turn_floor`` radians: a tracker's covariance is the fit's alone (measured on the
Intel log, ``docs/decisions/pose-graph.md``). With a ``local`` pose given to
:meth:`LoopCloser.add` (``scanlines.map.loopmap`` gives the pose of a second tracker on the
last ``submap_scans`` scans alone, :class:`~scanlines.map.submaps.LocalTracker`; 0, the
default, none), the tracking edges are its relative poses: tracked on the whole map, every
lap after the first follows the first lap's map, and its relative poses carry the first
lap's bend. Off by default: with 200 scans (and floors of 3 cm, 0.005 rad) it takes the
Intel log's ATE from 105 to 61 mm, but makes Freiburg 079's held-out map slightly worse
(``docs/decisions/pose-graph.md``).

Closures (:meth:`LoopCloser.close`): every ``every``-th scan (the *query*) is compared with
the scans at least ``min_travel`` metres of path before it whose estimated pose lies within
``radius``; the nearest is the candidate. The query's returns are aligned
(:func:`~scanlines.geometry.registration.icp`) to a *submap* of the old scan and its
``window`` neighbours either side, from the estimated relative pose and, if that fails,
from the old scan's pose (the query back where the old scan was). A candidate is accepted
when it passes, in turn:

* alignment quality: the inlier share at least ``min_inliers``, the inliers' RMS at most
  ``max_rms``, every direction pinned by the inliers (the smallest eigenvalue of their
  normal matrix, about the query's sensor with a turn weighed at a lever of 1 m, per
  inlier, at least ``least``: a corridor's axis is not);
* agreement with odometry: the correction it makes to the query's estimated pose, under the
  covariance the tracking edges accumulate between the two scans (plus the closure's own),
  within a squared Mahalanobis distance of ``gate``;
* agreement with the other closures: after the graph is optimised with every closure
  found, a closure whose error is above ``consistency`` (squared Mahalanobis) is dropped,
  the worst first, and the graph optimised again, until every closure left agrees.

Detection runs ``rounds`` times, each on the poses the previous round optimised.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar, NamedTuple

import numpy as np

from scanlines.geometry.poses import Pose, compose, relative_pose
from scanlines.geometry.registration import (
    IcpSettings,
    LineTarget,
    line_target,
    point_to_line_step,
    point_to_line_system,
    transform_points,
)
from scanlines.map.posegraph import Edge, PoseGraph, edge_errors, optimise
from scanlines.params import MAX_COUNT, MAX_METRES, MAX_SCANS, Param, integer, number
from scanlines.params.tables import Groups, SettingsTable

__all__ = ["Closure", "LoopCloser", "LoopResult", "LoopSettings", "Refusal"]


_METRES = number(low=0.0, high=MAX_METRES)
_POSITIVE_METRES = number(low=0.0, low_open=True, high=MAX_METRES)
_POSITIVE_RADIANS = number(low=0.0, low_open=True, high=math.pi)
_CHI_SQUARE = number(low=0.0, low_open=True)


class LoopSettings(SettingsTable):
    """The constants of loop closure (metres, radians; the module's note)."""

    groups: ClassVar[Groups] = {
        "candidates": {
            "every": Param(3, integer(1, MAX_SCANS), "every this many scans is a query"),
            "min_travel": Param(2.0, _METRES, "path before a query an old scan must be (m)"),
            "radius": Param(1.5, _METRES, "an old scan's estimated pose this near a query (m)"),
            "window": Param(5, integer(0, MAX_SCANS), "neighbours each side in the old submap"),
        },
        "verification": {
            "min_inliers": Param(0.7, number(low=0.0, high=1.0), "least inlier share"),
            "max_rms": Param(0.03, _METRES, "largest inliers' RMS (m)"),
            "least": Param(0.02, number(low=0.0), "least pinning of every direction"),
            "gate": Param(11.34, _CHI_SQUARE, "agreement with odometry (chi-square, 3 dof)"),
            "consistency": Param(11.34, _CHI_SQUARE, "agreement with the other closures"),
        },
        "weights": {
            "closure_sigma": Param(0.02, _POSITIVE_METRES, "a closure's position sigma (m)"),
            "closure_turn_sigma": Param(
                math.radians(0.5), _POSITIVE_RADIANS, "a closure's heading sigma (rad)"
            ),
            "edge_floor": Param(0.02, _METRES, "floor of a tracking edge's position sigma (m)"),
            "edge_turn_floor": Param(
                0.01, number(low=0.0, high=math.pi), "floor of its heading sigma (rad)"
            ),
        },
        "search": {
            "rounds": Param(2, integer(1, 100), "rounds of detection"),
            "max_points": Param(200, integer(2, MAX_COUNT), "a query's returns aligned, at most"),
            "submap_scans": Param(
                0, integer(0, MAX_SCANS), "tracking edges from the last scans' lines (0: off)"
            ),
        },
    }

    def closure_information(self) -> np.ndarray:
        s, t = self.closure_sigma, self.closure_turn_sigma
        return np.diag([1.0 / s**2, 1.0 / s**2, 1.0 / t**2])


class Closure(NamedTuple):
    """An accepted closure: the query scan ``j`` seen from the old scan ``i`` (their log
    indices and graph nodes), the relative pose found, the inlier share and RMS, the
    correction it made to the query's estimate (metres, degrees) and its squared
    Mahalanobis distance under the chain's covariance."""

    scan_i: int
    scan_j: int
    node_i: int
    node_j: int
    pose: Pose
    inliers: float
    rms: float
    correction_m: float
    correction_deg: float
    mahalanobis: float

    def to_dict(self) -> dict[str, Any]:
        d = self._asdict()
        d["pose"] = list(self.pose)
        return d


class Refusal(NamedTuple):
    """A candidate refused: the old and the query scan (log indices) and why."""

    scan_i: int
    scan_j: int
    reason: str


class LoopResult(NamedTuple):
    """The optimised poses (N x 3, in the order added), the closures accepted, the
    candidates refused, the candidates tried (a pair tried in each round counts each time),
    the solver's figures and the settings."""

    poses: np.ndarray
    closures: list[Closure]
    refusals: list[Refusal]
    candidates: int
    solver: dict[str, Any]
    settings: LoopSettings

    @property
    def refused(self) -> dict[str, int]:
        """The refusals counted by reason."""
        counts: dict[str, int] = {}
        for r in self.refusals:
            counts[r.reason] = counts.get(r.reason, 0) + 1
        return counts


class _Node(NamedTuple):
    index: int
    target: LineTarget | None
    points: np.ndarray | None


def _floored(cov: np.ndarray, floor: float, turn_floor: float) -> np.ndarray:
    c = np.array(cov, dtype=np.float64)
    c[0, 0] = max(c[0, 0], floor**2)
    c[1, 1] = max(c[1, 1], floor**2)
    c[2, 2] = max(c[2, 2], turn_floor**2)
    return c


class LoopCloser:
    """Collects tracked scans (:meth:`add`), then closes the loops (:meth:`close`)."""

    def __init__(self, settings: LoopSettings | None = None) -> None:
        self.settings = settings or LoopSettings()
        self._poses: list[Pose] = []
        self._covariances: list[np.ndarray] = []
        self._nodes: list[_Node] = []
        self._local: list[Pose] = []

    def __len__(self) -> int:
        return len(self._poses)

    def add(
        self, index: int, pose: Pose, covariance: np.ndarray, scan=None, local: Pose | None = None
    ) -> None:
        """A tracked scan (log ``index``) at ``pose`` with ``covariance`` (3 x 3); its
        ``scan`` gives closures (``None``: it does not). ``local``: its pose by another
        tracker (:class:`~scanlines.map.submaps.LocalTracker`), whose relative poses make
        the tracking edges instead of ``pose``'s (``covariance`` then that tracker's)."""
        s = self.settings
        self._poses.append(tuple(float(v) for v in pose))  # type: ignore[arg-type]
        self._local.append(self._poses[-1] if local is None else tuple(float(v) for v in local))
        self._covariances.append(_floored(covariance, s.edge_floor, s.edge_turn_floor))
        if scan is None:
            self._nodes.append(_Node(index, None, None))
            return
        target = line_target(scan)
        points = scan.points[scan.valid]
        if len(points) > s.max_points:
            points = points[np.linspace(0, len(points) - 1, s.max_points).round().astype(int)]
        self._nodes.append(_Node(index, target, np.array(points, dtype=np.float64)))

    def graph(self) -> PoseGraph:
        """The graph of the tracking edges alone, at the tracked poses."""
        graph = PoseGraph(np.array(self._poses, dtype=np.float64).reshape(-1, 3))
        for k in range(1, len(self._poses)):
            z = relative_pose(self._local[k - 1], self._local[k])
            graph.add(Edge(k - 1, k, z, np.linalg.inv(self._covariances[k])))
        return graph

    def close(self, progress: Callable[[int, int], None] | None = None) -> LoopResult:
        """Find, verify and optimise the closures; ``progress(done, total)`` per query."""
        s = self.settings
        poses = np.array(self._poses, dtype=np.float64).reshape(-1, 3)
        covariances = np.array(self._covariances).reshape(-1, 3, 3)
        found: dict[tuple[int, int], Closure] = {}
        refusals: list[Refusal] = []
        candidates = 0
        travel = self._travel()
        queries = _queries(self._nodes, s.every)
        total = s.rounds * len(queries)
        solver: dict[str, Any] = {}
        for round_ in range(s.rounds):
            for done, q in enumerate(queries, start=1):
                if progress is not None:
                    progress(round_ * len(queries) + done, total)
                o = _candidate(q, poses, travel, self._nodes, s)
                if o is None or (o, q) in found:
                    continue
                candidates += 1
                closure, reason = self._try(o, q, poses, covariances)
                if closure is None:
                    refusals.append(Refusal(self._nodes[o].index, self._nodes[q].index, reason))
                else:
                    found[(o, q)] = closure
            poses, kept, solver = self._optimise(found)
            for key in sorted(set(found) - kept):
                c = found.pop(key)
                refusals.append(Refusal(c.scan_i, c.scan_j, "disagrees with the other closures"))
        closures = sorted(found.values(), key=lambda c: (c.node_j, c.node_i))
        return LoopResult(poses, closures, refusals, candidates, solver, s)

    def _try(self, o: int, q: int, poses: np.ndarray, covariances: np.ndarray):
        """The closure of query node ``q`` to old node ``o``, or None and why not."""
        s = self.settings
        target = _submap(o, poses, self._nodes, s.window)
        fit = _register(self._nodes[q].points, target, poses[o], poses[q])
        if fit is None or fit.inlier_fraction < s.min_inliers or fit.rms > s.max_rms:
            return None, "alignment too poor"
        if fit.least < s.least:
            return None, "alignment leaves a direction free"
        moved = np.array(compose(tuple(poses[o]), fit.pose))
        delta = moved - poses[q]
        delta[2] = math.remainder(delta[2], 2.0 * math.pi)
        chain = _chain_covariance(o, q, poses, covariances)
        rot = _rotation(poses[o][2])
        own = np.linalg.inv(s.closure_information())
        chain = chain + rot @ own @ rot.T
        distance = float(delta @ np.linalg.solve(chain, delta))
        if distance > s.gate:
            return None, "disagrees with odometry"
        closure = Closure(
            self._nodes[o].index, self._nodes[q].index, o, q, fit.pose, fit.inlier_fraction,
            fit.rms, math.hypot(delta[0], delta[1]), math.degrees(abs(delta[2])), distance,
        )  # fmt: skip
        return closure, ""

    def _travel(self) -> np.ndarray:
        p = np.array(self._poses, dtype=np.float64).reshape(-1, 3)
        steps = np.hypot(*np.diff(p[:, :2], axis=0).T)
        return np.concatenate(([0.0], np.cumsum(steps)))

    def _optimise(self, found: dict[tuple[int, int], Closure]):
        """The graph optimised with the closures ``found``; those that disagree with the
        rest dropped (the worst first). Returns the poses, the closures kept, the figures."""
        import time

        s = self.settings
        kept = set(found)
        started = time.perf_counter()
        solves = 0
        while True:
            graph = self.graph()
            loops = sorted(kept)
            for key in loops:
                c = found[key]
                graph.add(Edge(c.node_i, c.node_j, c.pose, s.closure_information(), "loop"))
            solution = optimise(graph)
            solves += 1
            errors = edge_errors(graph, solution.poses)[len(graph.edges) - len(loops) :]
            if not len(loops) or errors.max() <= s.consistency:
                break
            kept.discard(loops[int(np.argmax(errors))])
        figures = {
            "solver": "Gauss-Newton, scipy.sparse LU", "poses": len(graph.poses),
            "edges": len(graph.edges), "solves": solves, "iterations": solution.iterations,
            "initial_cost": solution.initial_cost, "cost": solution.cost,
            "seconds": time.perf_counter() - started,
        }  # fmt: skip
        return solution.poses, kept, figures


def _queries(nodes: list[_Node], every: int) -> list[int]:
    with_points = [k for k, n in enumerate(nodes) if n.points is not None]
    return with_points[::every]


def _rotation(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _candidate(q: int, poses: np.ndarray, travel: np.ndarray, nodes, s: LoopSettings):
    """The old node nearest to ``q``'s estimate within ``radius``, ``min_travel`` back."""
    last = int(np.searchsorted(travel, travel[q] - s.min_travel, side="right"))
    if last <= 0:
        return None
    d = np.hypot(*(poses[:last, :2] - poses[q, :2]).T)
    order = np.argsort(d)
    for o in order[:20]:
        if d[o] > s.radius:
            return None
        if nodes[o].target is not None:
            return int(o)
    return None


def _submap(o: int, poses: np.ndarray, nodes: list[_Node], window: int) -> LineTarget:
    """The line targets of node ``o`` and its neighbours, in ``o``'s frame."""
    points, normals = [], []
    for k in range(max(0, o - window), min(len(nodes), o + window + 1)):
        target = nodes[k].target
        if target is None or not len(target.points):
            continue
        x, y, t = relative_pose(tuple(poses[o]), tuple(poses[k]))
        c, s = math.cos(t), math.sin(t)
        rot = np.array([[c, -s], [s, c]])
        points.append(target.points @ rot.T + (x, y))
        normals.append(target.normals @ rot.T)
    if not points:
        return LineTarget(np.zeros((0, 2)), np.zeros((0, 2)))
    return LineTarget(np.vstack(points), np.vstack(normals))


_ICP = IcpSettings(max_points=200, max_iterations=40)


class _Fit(NamedTuple):
    """An alignment: the pose, the inliers' RMS and share, and the least constraint per
    inlier of any direction of ``(x, y, theta * 1 m)`` (the smallest eigenvalue of the
    normal matrix over the inliers)."""

    pose: Pose
    rms: float
    inlier_fraction: float
    least: float
    normal: np.ndarray


def _register(points, target: LineTarget, old: np.ndarray, query: np.ndarray):
    """The query's points aligned to the old submap: from the estimated relative pose,
    then (if that is poor) from the old scan's pose (the query back where it was)."""
    from scipy.spatial import cKDTree

    if points is None or len(target.points) < 3:
        return None
    tree = cKDTree(target.points)
    fit = _icp(points, target, tree, relative_pose(tuple(old), tuple(query)))
    if fit.inlier_fraction >= 0.7:
        return fit
    other = _icp(points, target, tree, (0.0, 0.0, 0.0))
    return other if other.inlier_fraction > fit.inlier_fraction else fit


def _icp(points: np.ndarray, target: LineTarget, tree, initial: Pose) -> _Fit:
    """:func:`~scanlines.geometry.registration.icp`'s point-to-line steps and coarse-to-fine
    gate (:data:`_ICP`), the nearest target point found by a k-d tree."""
    s, pose, gate = _ICP, initial, _ICP.max_distance
    for _ in range(s.max_iterations):
        moved = transform_points(points, pose)
        distance, index = tree.query(moved, distance_upper_bound=gate)
        ok = np.isfinite(distance)
        if np.count_nonzero(ok) < 3:
            break
        p, q, n = moved[ok], target.points[index[ok]], target.normals[index[ok]]
        e = np.sum(n * (p - q), axis=1)
        step = point_to_line_step(p, n, e, s.huber, ridge=1e-6).update
        pose = compose((step[0], step[1], step[2]), pose)
        size = float(np.abs(step).max())
        if gate <= s.min_distance and size < s.tolerance:
            break
        if size < 1e-3:
            gate = max(s.min_distance, gate * s.shrink)
    moved = transform_points(points, pose)
    distance, index = tree.query(moved, distance_upper_bound=s.min_distance)
    ok = np.isfinite(distance)
    e = np.sum(target.normals[index[ok]] * (moved[ok] - target.points[index[ok]]), axis=1)
    inlier = np.abs(e) <= s.inlier_residual
    n_in = int(np.count_nonzero(inlier))
    if n_in < 3:
        return _Fit(pose, math.inf, n_in / len(points), 0.0, np.eye(3))
    p, n = moved[ok][inlier], target.normals[index[ok]][inlier]
    h = point_to_line_system(p - np.array(pose[:2]), n, e[inlier], s.huber).normal
    least = float(np.linalg.eigvalsh(h)[0]) / n_in
    rms = float(np.sqrt(np.mean(e[inlier] ** 2)))
    return _Fit(pose, rms, n_in / len(points), least, h)


def _chain_covariance(o: int, q: int, poses: np.ndarray, covariances: np.ndarray):
    """The covariance (world frame) of pose ``q`` given pose ``o``, accumulated along the
    tracking edges ``o+1 .. q`` (first order)."""
    k = np.arange(o + 1, q + 1)
    theta = poses[k - 1, 2]
    c, s = np.cos(theta), np.sin(theta)
    lever = poses[q, :2] - poses[k, :2]
    g = np.zeros((len(k), 3, 3))
    g[:, 0, 0], g[:, 0, 1], g[:, 1, 0], g[:, 1, 1] = c, -s, s, c
    g[:, 0, 2], g[:, 1, 2], g[:, 2, 2] = -lever[:, 1], lever[:, 0], 1.0
    return np.einsum("kab,kbc,kdc->ad", g, covariances[k], g)
