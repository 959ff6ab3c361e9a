"""Exact ground truth of a simulated scan: breakpoints, corners and true segments.

Conventions (they follow the project's, see ``METHOD.md``):

* A beam is a **true return** when its measured range is a return of the surface the
  beam hits (:attr:`BeamStatus.HIT`). Beams with no return (nothing hit, dropout,
  out of range) and beams whose return belongs to no surface (outliers, mixed pixels)
  are all *missing* for the truth events; outliers and mixed pixels are listed
  separately (:attr:`Truth.outliers`, :attr:`Truth.mixed_pixels`).
* Surfaces: every edge of a line shape is its own surface; all edges of a curved
  shape (a round pillar, ``is_line=False``) together form one surface.
* For consecutive true returns ``i < j`` (skipping missing beams):

  - two or more missing beams between them: a **breakpoint** at ``i``;
  - else the same surface: continuous (so one missing beam inside a wall is bridged);
  - else two adjacent edges of one line shape (sharing a vertex): a **corner**, at
    ``i`` or ``j``, whichever hit point is nearer the shared vertex (``i`` on a tie);
  - else (different surfaces that do not meet): a **breakpoint** at ``i``.

* The first and last beams of a partial scan are not events. In a full-circle scan
  (:func:`scanlines.scan.is_full_circle`) the last true return is followed by the
  first, across the seam, like any other pair.
* **True segments** are the maximal runs of true returns between events on line
  edges (runs on curved surfaces are not segments). A segment's ``first``/``last``
  are its first/last beam (``first > last`` for the one run that crosses the seam of
  a full-circle scan), ``rho``/``alpha`` the Hesse form of the true edge line in the
  sensor frame (``rho >= 0``), ``start``/``end`` the exact hit points of its
  first/last beam.
* Every event records the number of true returns in the run before and after it
  (``*_runs``), so that scoring can treat events next to tiny runs as "don't care".
* **Don't-care events** (:attr:`Truth.breakpoint_dont_care`,
  :attr:`Truth.corner_dont_care`), events that are real in the world but that no
  extractor can be asked to find:

  - a **junction**: a breakpoint between two surfaces that touch (an edge end of one
    lies on an edge end of the other, as where a straight wall runs into a curved
    one): there is no depth step, and a line meeting a curve has no corner;
  - a **depth step hidden by the noise** (only when the range noise is given): a
    breakpoint between consecutive returns ``i`` on surface ``A`` and ``j`` on
    surface ``B`` (fewer than two missing beams between them) where each return looks
    like the continuation of the other surface: the step
    ``d = max(|r_j - r_A(j)|, |r_i - r_B(i)|)``, with ``r_X(k)`` the range along beam
    ``k`` to the infinite line of the edge of ``X`` hit, is below
    ``3 sqrt(sigma(r_i)**2 + sigma(r_j)**2)``;
  - a **turn hidden by the noise** (only when the range noise is given): a corner
    whose turn (angle between the two edges' directions along the outline, 0 for
    straight on) is below ``3 sqrt(s_1**2 + s_2**2)``, where ``s_k`` is the standard
    error of the direction of a line fitted to side ``k``'s true returns:
    ``s_k**2 = mean(sigma_perp**2) / sum((t - mean(t))**2)``, ``t`` the positions of
    the side's hit points along its edge and ``sigma_perp = sigma(r) cos(incidence)``
    the range noise normal to the side (for ``n`` points evenly spread over a length
    ``L``, ``s = sigma sqrt(12 / n) / L`` roughly).

  ``sigma(r)`` is the 1-sigma of a measured range at ``r``
  (:meth:`~scanlines.sim.noise.NoiseModel.effective_sigma`: Gaussian noise and
  quantisation).

The types (:class:`~scanlines.evaluation.truth.Truth`, its
:class:`~scanlines.evaluation.truth.TrueSegments` and
:class:`~scanlines.evaluation.truth.BeamStatus`) belong to the evaluation, which scores
against them; this module computes them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from scanlines.sim.world import World
from scanlines.truth import BeamStatus, TrueSegments, Truth

__all__ = ["compute_truth", "hesse_line", "sensor_to_world", "world_to_sensor"]

_NONE, _BREAK, _CORNER = 0, 1, 2
# Edge ends closer than this (metres) touch: a junction, not a depth step.
_TOUCH = 1e-6
# How many standard deviations an event must clear to count (steps and turns).
HIDDEN_K = 3.0


def _readonly(values: np.ndarray) -> np.ndarray:
    values.setflags(write=False)
    return values


def sensor_to_world(points: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
    """Map ``K x 2`` sensor-frame points to the world frame."""
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return np.column_stack((x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]))


def world_to_sensor(points: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
    """Map ``K x 2`` world-frame points to the sensor frame."""
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2) - (x, y)
    return np.column_stack((c * p[:, 0] + s * p[:, 1], -s * p[:, 0] + c * p[:, 1]))


def hesse_line(start: np.ndarray, end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hesse form ``(rho, alpha)`` of the lines through ``start[k]`` and ``end[k]``.

    ``x cos(alpha) + y sin(alpha) = rho`` with ``rho >= 0`` and ``alpha`` in
    ``(-pi, pi]``.
    """
    a = np.asarray(start, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(end, dtype=np.float64).reshape(-1, 2)
    d = b - a
    normal = np.column_stack((-d[:, 1], d[:, 0])) / np.hypot(d[:, 0], d[:, 1])[:, None]
    rho = np.einsum("ij,ij->i", normal, a)
    flip = rho < 0
    normal[flip] *= -1.0
    rho = np.abs(rho)
    alpha = np.arctan2(normal[:, 1], normal[:, 0])
    alpha = np.where(alpha <= -math.pi, alpha + 2 * math.pi, alpha) + 0.0  # no -0.0
    return rho, alpha


@dataclass(frozen=True)
class _Pairs:
    """Consecutive true returns ``left[k] -> right[k]`` and what lies between them."""

    left: np.ndarray
    right: np.ndarray
    kind: np.ndarray


def _classify_pairs(
    world: World, returns: np.ndarray, edge: np.ndarray, n: int, circle: bool
) -> _Pairs:
    if circle and len(returns) >= 1:
        left, right = returns, np.roll(returns, -1)
    else:
        left, right = returns[:-1], returns[1:]
    missing = (right - left - 1) % n
    key = world.surface_key(edge)
    same = key[left] == key[right]
    adjacent = world.adjacent(edge[left], edge[right]) & world.edge_is_line[edge[left]]
    adjacent &= world.edge_is_line[edge[right]]
    kind = np.where(same, _NONE, np.where(adjacent, _CORNER, _BREAK))
    kind = np.where(missing >= 2, _BREAK, kind)
    return _Pairs(left, right, kind.astype(np.int8))


def _runs(n_returns: int, event_pos: np.ndarray, circle: bool) -> tuple[np.ndarray, np.ndarray]:
    """Start position and length (in true returns) of each run between events.

    ``event_pos[k]`` is the position (in the list of true returns) after which event
    ``k`` occurs. Run ``k`` is the one after event ``k - 1`` (linear: run 0 starts the
    scan); in a circle run ``k`` is the one after event ``k``.
    """
    if circle:
        if len(event_pos) == 0:
            return np.array([0]), np.array([n_returns])
        starts = (event_pos + 1) % n_returns
        lengths = np.diff(np.append(event_pos, event_pos[0] + n_returns))
        return starts, lengths
    starts = np.concatenate(([0], event_pos + 1))
    ends = np.append(event_pos, n_returns - 1)
    return starts, ends - starts + 1


def _event_runs(lengths: np.ndarray, n_events: int, circle: bool) -> np.ndarray:
    """``K x 2`` run length before and after each event."""
    if circle:
        if n_events == 0:
            return np.empty((0, 2), np.intp)
        return np.column_stack((np.roll(lengths, 1), lengths)).reshape(-1, 2)
    return np.column_stack((lengths[:-1], lengths[1:])).reshape(-1, 2)


def _true_segments(
    world: World,
    pose: tuple[float, float, float],
    returns: np.ndarray,
    edge: np.ndarray,
    hit_points: np.ndarray,
    run_starts: np.ndarray,
    run_lengths: np.ndarray,
) -> TrueSegments:
    """The runs on line edges, as segments."""
    m = len(returns)
    if m == 0:
        run_starts = run_lengths = np.empty(0, np.intp)
    first = returns[run_starts % max(m, 1)] if m else np.empty(0, np.intp)
    last = returns[(run_starts + run_lengths - 1) % max(m, 1)] if m else np.empty(0, np.intp)
    on_line = world.edge_is_line[edge[first]] if m else np.empty(0, bool)
    first, last, n_ret = first[on_line], last[on_line], run_lengths[on_line]
    seg_edge = edge[first]
    a = world_to_sensor(world.edge_start[seg_edge], pose)
    b = world_to_sensor(world.edge_end[seg_edge], pose)
    rho, alpha = hesse_line(a, b)
    return TrueSegments(
        first=_readonly(first.astype(np.intp)),
        last=_readonly(last.astype(np.intp)),
        edge=_readonly(seg_edge.astype(np.intp)),
        n_returns=_readonly(n_ret.astype(np.intp)),
        rho=_readonly(rho),
        alpha=_readonly(alpha),
        start=_readonly(hit_points[first].reshape(-1, 2).copy()),
        end=_readonly(hit_points[last].reshape(-1, 2).copy()),
    )


def _corner_beams(
    world: World,
    pose: tuple[float, float, float],
    edge: np.ndarray,
    hit_points: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Beam of each corner (``left`` or ``right``, whichever hit is nearer the vertex).

    Returns the beams and the ``C x 2`` shared vertices in the sensor frame.
    """
    vertices = world_to_sensor(world.shared_vertex(edge[left], edge[right]), pose)
    d_left = np.hypot(*(hit_points[left] - vertices).T).reshape(-1)
    d_right = np.hypot(*(hit_points[right] - vertices).T).reshape(-1)
    return np.where(d_left <= d_right, left, right), vertices


def _incidence(world: World, edge: np.ndarray, world_angles: np.ndarray) -> np.ndarray:
    out = np.full(len(edge), np.nan)
    hit = edge >= 0
    if not hit.any():
        return out
    normals = world.edge_normals()[edge[hit]]
    cos_inc = np.abs(
        np.cos(world_angles[hit]) * normals[:, 0] + np.sin(world_angles[hit]) * normals[:, 1]
    )
    out[hit] = np.arccos(np.clip(cos_inc, 0.0, 1.0))
    return out


def _runs_around_events(
    n_returns: int, run_lengths: np.ndarray, n_events: int, full_circle: bool
) -> np.ndarray:
    """The runs before and after each event (none without returns)."""
    if not n_returns:
        return np.empty((0, 2), np.intp)
    return _event_runs(run_lengths, n_events, full_circle)


def _hit_points(edge: np.ndarray, r: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Each beam's exact hit in the sensor frame, NaN where it hits no edge."""
    with np.errstate(invalid="ignore"):
        return np.where(
            (edge >= 0)[:, None], np.column_stack((r * np.cos(theta), r * np.sin(theta))), np.nan
        ).reshape(len(edge), 2)


def _dont_care(
    world: World,
    pose: tuple[float, float, float],
    edge: np.ndarray,
    r: np.ndarray,
    theta: np.ndarray,
    hit_points: np.ndarray,
    incidence: np.ndarray,
    returns: np.ndarray,
    run_starts: np.ndarray,
    run_lengths: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    is_break: np.ndarray,
    is_corner: np.ndarray,
    full_circle: bool,
    sigma: Callable[[np.ndarray], np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Which breakpoints and which corners (events ``left``, ``right``) are don't care:
    junctions; with ``sigma``, also depth steps and turns the noise hides."""
    n = len(edge)
    gap = (right - left - 1) % n
    bp_dont_care = _junction(world, edge[left[is_break]], edge[right[is_break]])
    bp_dont_care &= gap[is_break] < 2
    corner_dont_care = np.zeros(int(np.count_nonzero(is_corner)), bool)
    if sigma is not None and len(returns):
        lines = _sensor_lines(world, pose)
        bp_dont_care |= _hidden_step(
            lines, edge, r, theta, left[is_break], right[is_break], gap[is_break], sigma
        )
        side_runs = _side_runs(len(left), full_circle)[is_corner]
        corner_dont_care = _hidden_turn(
            world, pose, edge, hit_points, r, incidence, returns, run_starts, run_lengths,
            side_runs, left[is_corner], right[is_corner], sigma,
        )  # fmt: skip
    return bp_dont_care, corner_dont_care


def compute_truth(
    world: World,
    pose: tuple[float, float, float],
    angles: np.ndarray,
    edge: np.ndarray,
    true_ranges: np.ndarray,
    status: np.ndarray,
    *,
    full_circle: bool,
    sigma: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Truth:
    """Ground truth of one scan (a :class:`Truth`) from its exact hits and beam statuses.

    Parameters
    ----------
    world:
        The world the scan was taken in.
    pose:
        Sensor pose ``(x, y, theta)`` in the world frame.
    angles:
        Beam bearings in the sensor frame.
    edge, true_ranges:
        Edge hit by each beam and the exact range (``-1`` / ``inf`` for none).
    status:
        :class:`BeamStatus` of each beam.
    full_circle:
        Whether the scan closes the circle.
    sigma:
        1-sigma of a measured range as a function of the range (the sensor's
        :meth:`~scanlines.sim.noise.NoiseModel.effective_sigma`); with it, depth
        steps and turns the noise hides are don't care (module docstring). ``None``:
        only junctions are don't care.
    """
    pose = (float(pose[0]), float(pose[1]), float(pose[2]))
    edge = np.asarray(edge, dtype=np.intp)
    r = np.asarray(true_ranges, dtype=np.float64)
    theta = np.asarray(angles, dtype=np.float64)
    n = len(edge)
    hit_points = _hit_points(edge, r, theta)
    status = np.asarray(status, dtype=np.int8)
    returns = np.flatnonzero((status == BeamStatus.HIT) & (edge >= 0))
    pairs = _classify_pairs(world, returns, edge, n, full_circle)
    event_pos = np.flatnonzero(pairs.kind != _NONE)
    run_starts, run_lengths = _runs(len(returns), event_pos, full_circle)
    runs = _runs_around_events(len(returns), run_lengths, len(event_pos), full_circle)
    kinds = pairs.kind[event_pos]
    is_break, is_corner = kinds == _BREAK, kinds == _CORNER
    left, right = pairs.left[event_pos], pairs.right[event_pos]
    corner_beam, vertices = _corner_beams(
        world, pose, edge, hit_points, left[is_corner], right[is_corner]
    )
    bp_order = np.argsort(left[is_break], kind="stable")
    c_order = np.argsort(corner_beam, kind="stable")
    incidence = _incidence(world, edge, theta + pose[2])
    bp_dont_care, corner_dont_care = _dont_care(
        world, pose, edge, r, theta, hit_points, incidence, returns, run_starts, run_lengths,
        left, right, is_break, is_corner, full_circle, sigma,
    )  # fmt: skip
    return Truth(
        n_beams=n,
        full_circle=bool(full_circle),
        pose=pose,
        edge=_readonly(edge.copy()),
        true_ranges=_readonly(r.copy()),
        hit_points=_readonly(hit_points),
        incidence=_readonly(incidence),
        on_curve=_readonly(world.surface_key(edge) >= world.n_edges),
        status=_readonly(status.copy()),
        breakpoints=_readonly(left[is_break][bp_order].astype(np.intp)),
        breakpoint_runs=_readonly(runs[is_break][bp_order].astype(np.intp)),
        corners=_readonly(corner_beam[c_order].astype(np.intp)),
        corner_points=_readonly(vertices[c_order]),
        corner_runs=_readonly(runs[is_corner][c_order].astype(np.intp)),
        segments=_true_segments(world, pose, returns, edge, hit_points, run_starts, run_lengths),
        breakpoint_dont_care=_readonly(bp_dont_care[bp_order]),
        corner_dont_care=_readonly(corner_dont_care[c_order]),
    )


# --------------------------------------------------------------------------- don't care


def _sensor_lines(world: World, pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Hesse form ``(rho, alpha)`` of every edge's line in the sensor frame."""
    if world.n_edges == 0:
        return np.empty(0), np.empty(0)
    a = world_to_sensor(world.edge_start, pose)
    b = world_to_sensor(world.edge_end, pose)
    return hesse_line(a, b)


def _junction(world: World, edge_a: np.ndarray, edge_b: np.ndarray) -> np.ndarray:
    """Pairs of edges (of different shapes or surfaces) that touch end to end."""
    out = np.zeros(len(edge_a), bool)
    if len(edge_a) == 0:
        return out
    ends_a = (world.edge_start[edge_a], world.edge_end[edge_a])
    ends_b = (world.edge_start[edge_b], world.edge_end[edge_b])
    for p in ends_a:
        for q in ends_b:
            out |= np.hypot(*(p - q).T) <= _TOUCH
    return out


def _range_to_line(rho: np.ndarray, alpha: np.ndarray, bearing: np.ndarray) -> np.ndarray:
    """Range along ``bearing`` to the line ``(rho, alpha)``; inf when the ray misses it."""
    c = np.cos(bearing - alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(c > 1e-9, rho / np.where(c > 1e-9, c, 1.0), np.inf)


def _hidden_step(
    lines: tuple[np.ndarray, np.ndarray],
    edge: np.ndarray,
    r: np.ndarray,
    theta: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    gap: np.ndarray,
    sigma: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """Breakpoints whose depth step is below ``HIDDEN_K`` combined sigmas."""
    if len(left) == 0:
        return np.zeros(0, bool)
    rho, alpha = lines
    a, b = edge[left], edge[right]
    a_at_right = _range_to_line(rho[a], alpha[a], theta[right])
    b_at_left = _range_to_line(rho[b], alpha[b], theta[left])
    with np.errstate(invalid="ignore"):
        step = np.maximum(np.abs(r[right] - a_at_right), np.abs(r[left] - b_at_left))
    combined = np.hypot(sigma(r[left]), sigma(r[right]))
    return np.isfinite(step) & (gap < 2) & (step < HIDDEN_K * combined)


def _side_runs(n_events: int, circle: bool) -> np.ndarray:
    """``K x 2``: the run (index into the runs of :func:`_runs`) before and after each event."""
    k = np.arange(n_events)
    if circle:
        return np.column_stack((k - 1, k)) % max(n_events, 1)
    return np.column_stack((k, k + 1))


def _direction_variance(points: np.ndarray, direction: np.ndarray, sigma_perp: np.ndarray) -> float:
    """Variance of the direction of a line fitted to ``points`` (radians squared)."""
    t = points @ direction
    spread = float(((t - t.mean()) ** 2).sum()) if len(t) else 0.0
    return float(np.mean(sigma_perp**2)) / spread if spread > 0 else math.inf


def _hidden_turn(
    world: World,
    pose: tuple[float, float, float],
    edge: np.ndarray,
    hit_points: np.ndarray,
    r: np.ndarray,
    incidence: np.ndarray,
    returns: np.ndarray,
    run_starts: np.ndarray,
    run_lengths: np.ndarray,
    side_runs: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    sigma: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """Corners whose turn is below ``HIDDEN_K`` times the sides' direction errors."""
    out = np.zeros(len(left), bool)
    m = len(returns)
    d = world_to_sensor(world.edge_end, pose) - world_to_sensor(world.edge_start, pose)
    for k in range(len(left)):
        e_l, e_r = edge[left[k]], edge[right[k]]
        first, second = (e_l, e_r) if world.next_edge[e_l] == e_r else (e_r, e_l)
        u, v = d[first], d[second]
        cos_turn = float(u @ v) / (math.hypot(*u) * math.hypot(*v))
        turn = math.acos(min(1.0, max(-1.0, cos_turn)))
        variance = 0.0
        for run, e in zip(side_runs[k], (e_l, e_r), strict=True):
            beams = returns[(run_starts[run] + np.arange(run_lengths[run])) % m]
            perp = sigma(r[beams]) * np.cos(incidence[beams])
            variance += _direction_variance(hit_points[beams], d[e] / math.hypot(*d[e]), perp)
        out[k] = turn < HIDDEN_K * math.sqrt(variance)
    return out
