"""The compiled steps the tests call directly (``scanlines._core``), with the argument
conversions and documentation of each; the package itself reaches them only through its
methods' kernels."""

from __future__ import annotations

import numpy as np

from scanlines import _core
from scanlines._core import Sweep
from scanlines.steps.arrays import bools, float64s, int64s
from scanlines.steps.breakpoints import BreakpointRule
from scanlines.steps.fit import PAPER, Moments, RunCost
from scanlines.steps.noise import NoiseLine
from scanlines.steps.returns import Returns


def _returns(returns: Returns) -> tuple[np.ndarray, ...]:
    index, r, x, y = returns
    return int64s(index), float64s(r), float64s(x), float64s(y)


def break_flags(returns: Returns, gap: np.ndarray, step: float, rule: BreakpointRule):
    """For each pair of consecutive positions, True where a cluster ends.

    A pair further apart than :func:`threshold` still continues its cluster where the
    rule's line tolerance is on and the pair continues the line of the pair before and
    of the pair after: the next return lies within the tolerance (grown with how far it
    is extrapolated) of the line through the two before it, and the pair's step is at
    most 2.5 times the shorter neighbouring step plus the tolerance (grazing walls grow
    their spacing smoothly; a jump does not). Returns on a wall seen at grazing incidence
    are far apart but collinear and evenly spaced, so a distance threshold alone cuts the
    wall; a depth jump or a spike is neither.
    """
    return _core.break_flags(*returns, int64s(gap), float(step), rule)


def threshold(rule: BreakpointRule, r_from: float, r_to: float, gap: int, step: float) -> float:
    """Largest distance ``D`` between returns ``r_from`` and ``r_to``, ``gap`` beams apart
    (the rules of the module docstring; the noise margin ``margin_sigmas`` times the
    noise at ``r_from``)."""
    return _core.threshold(rule, float(r_from), float(r_to), int(gap), float(step))


def cluster_returns(
    returns: Returns,
    n_beams: int,
    step: float,
    full_circle: bool,
    rule: BreakpointRule,
    ring_window: int,
    known_breaks: np.ndarray,
):
    """Clusters of one scan's returns, the seam of a full circle joined (module docstring).

    ``known_breaks`` are the break flags of ``returns`` if already computed (else an
    empty array); ``ring_window`` the points fitted on each side when a ring is
    anchored.

    Returns ``(returns, start, end, breakpoints, ring)``: the returns (rotated for a
    full circle), the clusters' inclusive bounds, the breakpoint beams and whether
    the scan is one closed ring.
    """
    rotated, start, end, breakpoints, ring = _core.cluster_returns(
        *returns, int(n_beams), float(step), bool(full_circle), rule, int(ring_window),
        bools(known_breaks),
    )  # fmt: skip
    return Returns(*rotated), start, end, breakpoints, ring


def break_beams(index: np.ndarray, end: np.ndarray, at_seam: bool) -> np.ndarray:
    """Breakpoint beams: the last beam of each cluster but the last (and it too when
    ``at_seam``, a full circle whose seam is a break)."""
    count = len(end) if at_seam else len(end) - 1
    return np.sort(index[end[:count]])


def cluster_bounds(breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inclusive ``start, end`` positions of the runs between ``breaks`` (flags per pair)."""
    cut = np.flatnonzero(breaks)
    return np.r_[0, cut + 1].astype(np.int64), np.r_[cut, len(breaks)].astype(np.int64)


def peak_positions(score, start, end) -> np.ndarray:
    """Positions ``i`` with ``|s_i| > |s_{i-1}|`` and ``|s_i| > |s_{i+1}|`` inside a cluster."""
    return _core.peak_positions(float64s(score), int64s(start), int64s(end))


def turn_scores(x, y, moments: Moments, start, end, window: int) -> np.ndarray:
    """Absolute turn (radians) between lines fitted to ``window`` points on each side.

    The line before ``p``, ``[p - w, p]``, is the line after ``p - w``: each run is
    fitted once, except the shortened ones at a cluster's ends.
    """
    return _core.turn_scores(float64s(x), float64s(y), *moments, int64s(start), int64s(end), window)


def slope_scores(r, gap, step: float, start, end, signed: bool) -> np.ndarray:
    """Eq. 13 at every position (0 where a neighbour lies outside the cluster, or a zero
    range gives no slope); ``signed`` leaves out the printed absolute values."""
    return _core.slope_scores(
        float64s(r), int64s(gap), float(step), int64s(start), int64s(end), signed
    )


def denoise(returns: Returns, n_beams: int, step: float, full_circle: bool,
            rule: BreakpointRule, kind: int, window: int, min_cluster_points: int,
            margin: float) -> tuple[Returns, np.ndarray, np.ndarray]:  # fmt: skip
    """Steps 2-3 by ``kind`` (:data:`ISOLATED`, :data:`LITERAL` or :data:`NO_DENOISE`).

    ``window`` is the literal rule's mean-filter window, ``min_cluster_points`` the
    smallest cluster the isolated rule keeps and ``margin`` the breakpoint margin the
    two-return test allows. Returns the cleaned returns, the beams dropped as noise
    and the break flags of the cleaned returns when known (empty otherwise).

    The isolated rule drops the spikes, then (with ``min_cluster_points > 1``) the returns
    of clusters smaller than that once the spikes are gone (the breakpoint test redone
    without them) and, with ``min_cluster_points == 2``, of the two-return clusters in
    between (:func:`in_between_clusters`).
    """
    cleaned, outliers, breaks = _core.denoise(
        _returns(returns), int(n_beams), float(step), bool(full_circle), tuple(rule),
        int(kind), int(window), int(min_cluster_points), float(margin),
    )  # fmt: skip
    return Returns(*cleaned), outliers, breaks


def in_between_clusters(r, gap, breaks, small, margin: float) -> np.ndarray:
    """Mask of the returns of two-return clusters that lie in depth between their neighbours.

    A mixed pixel is a return between the two surfaces of a depth jump; two of them, or one
    with the last return of the near surface cut off by the jump, make a cluster of two
    whose ranges lie between the facing returns of the clusters on either side (within
    ``margin``). A small object in front of a wall is nearer than both sides and stays.
    Only clusters whose neighbours are at most one missing beam away, and are not ``small``
    themselves, are judged.
    """
    return _core.in_between_clusters(
        float64s(r), int64s(gap), bools(breaks), bools(small), float(margin)
    )


def window_means(x, y, noise, window: int, breaks) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: noise point ``i`` and its neighbours become the mean of ``window`` points.

    The window ``[i - window//2, i - window//2 + window - 1]`` is clipped to the
    raw cluster of ``i`` (``breaks`` from the raw data), and neighbours across a
    raw break are left alone. Left neighbours are moved first, then the points, then
    right neighbours: where two windows overlap, a point takes the mean of the noise
    point to its left. Returns the moved coordinates.
    """
    return _core.window_means(float64s(x), float64s(y), bools(noise), int(window), bools(breaks))


def isolated_noise(returns: Returns, gap, step: float, rule: BreakpointRule, breaks) -> np.ndarray:
    """Points cut off from both neighbours that are themselves continuous (a spike).

    ``breaks`` are the :func:`~scanlines.steps.breakpoints.break_flags` of ``returns``;
    the two neighbours must be at most two beams apart (no beam missing beside the point).
    """
    return _core.isolated_noise(
        _returns(returns), int64s(gap), float(step), tuple(rule), bools(breaks)
    )


def literal_noise(d) -> np.ndarray:
    """Step 2 as written, on neighbour distances ``d`` (length n - 1): a mask of n points."""
    return _core.literal_noise(float64s(d))


def junction_events(
    returns: Returns, fit: int, moments: Moments, a, b, owner, shared: bool, ring: bool,
    sigma: float, turn_sigma,
):  # fmt: skip
    """Beams of the corners where two kept segments of one cluster meet, and of jumps.

    A shared corner is its shared point; otherwise the point nearer the two
    lines' intersection among those between the segments. With ``sigma >= 0``,
    two segments whose lines do not meet near their facing ends (farther than twice
    the local spacing plus three ``sigma``) are two surfaces at different depths joined
    by a mixed pixel or a small step: the junction is reported as a breakpoint (the last
    beam of the first segment). Given ``turn_sigma`` (the standard deviation of each
    segment's direction; empty: no test), a junction whose lines turn by less than
    :data:`CORNER_SIGMAS` times the standard deviation of the turn is not a corner: the
    noise hides it (the rule by which the simulator's truth makes such a turn
    don't-care).
    """
    return _core.junction_events(
        *returns, int(fit), *moments, int64s(a), int64s(b), int64s(owner), bool(shared),
        bool(ring), float(sigma), float64s(turn_sigma),
    )  # fmt: skip


def segment_events(
    returns: Returns, n_beams: int, moments: Moments, a, b, group, clustered: bool,
    wrap: bool, bounds: tuple[int, float, float],
):  # fmt: skip
    """Corners and breakpoints between consecutive segments ``[a, b]`` (module docstring).

    ``clustered``: only segments of one ``group`` can meet and no breakpoints are
    derived (the method's clustering has them); ``wrap``: the last segment is
    followed by the first, across the seam. ``bounds`` is ``(corner_beams,
    corner_distance, corner_angle)`` in beams, metres and radians.

    A corner is reported at the return nearest the lines' intersection among those from
    ``corner_beams`` positions before the first segment's last return to as many after
    the second's first; the candidates run on to the widest span between the facing
    ends of any pair of the scan (how the first, vectorised implementation searched:
    every published figure of the comparison methods was measured with it).

    Returns ``corners, breakpoints``, sorted distinct beams.
    """
    beams, distance, angle = bounds
    return _core.segment_events(
        *returns, int(n_beams), *moments, int64s(a), int64s(b), int64s(group), bool(clustered),
        bool(wrap), int(beams), float(distance), float(angle),
    )  # fmt: skip


def hesse_difference(rho_1: float, alpha_1: float, rho_2: float, alpha_2: float):
    """``(rho_1 - rho_2, alpha_1 - alpha_2)`` of two Hesse lines, the angle wrapped; of the
    two forms of a line through the origin, the one with the smaller angle difference."""
    return _core.hesse_difference(rho_1, alpha_1, rho_2, alpha_2)


def paper_run(moments: Moments, a: int, b: int) -> tuple[float, float, float]:
    """The paper's fit (eq. 15-17) of run ``[a, b]``: ``(rho, alpha, sse)``."""
    return fit_run(PAPER, moments, a, b)


def fit_run(fit: int, moments: Moments, a: int, b: int) -> tuple[float, float, float]:
    """Line ``(rho, alpha, sse)`` of run ``[a, b]`` by fit code (:data:`TLS` or
    :data:`PAPER`). The total-least-squares normal comes from the half-angle formulas of
    the scatter (no trigonometric call); the paper's fit is eq. 15-17 on the five sub-set
    means of the run, its ``sse`` eq. 14, NaN when the line has no slope. NaN for an
    empty run."""
    return _core.fit_run(fit, *moments, a, b)


def merge_by_chi_square(
    returns: Returns, moments: Moments, a, b, group, sigma, threshold: float, inflate: bool
):
    """Merge neighbouring runs of one group while their lines pass the chi-square test.

    The pair with the smallest chi-square below ``threshold`` is merged (the runs
    and everything between them), refitted, and the test repeated; ``sigma`` is the
    range noise of each return, ``inflate`` as :func:`~scanlines.steps.fit.run_covariances`
    takes it. Returns new ``a, b, group`` arrays.
    """
    return _core.merge_by_chi_square(
        *returns, *moments, int64s(a), int64s(b), int64s(group), float64s(sigma), float(threshold),
        bool(inflate),
    )  # fmt: skip


def parabola_at_centre(index, r, a: int, b: int, i: int, sums) -> tuple[float, float, float]:
    """Least-squares parabola of ``r`` over the beam offsets ``index - index[i]`` of
    positions ``a..b`` (``sums``: their :func:`offset_power_sums`): ``(r[i] - fit at i,
    leverage of i, slope at i per beam)``."""
    return _core.parabola_at_centre(int64s(index), float64s(r), a, b, i, tuple(sums))


def offset_power_sums(index: np.ndarray, a: int, b: int, i: int) -> tuple[float, ...]:
    """Sums of ``t^0 .. t^4`` over the beam offsets ``t = index[p] - index[i]`` of
    positions ``a..b``."""
    return _core.offset_power_sums(int64s(index), a, b, i)


def sweep_levels(cost: RunCost, start, end, candidates, scores, grid, use_grid: bool,
                 max_evaluations: int, shared: bool):  # fmt: skip
    """Score every cut of the clusters ``[start, end]`` at ``candidates`` that a threshold makes.

    Thresholds are nested (a lower one keeps every corner of a higher one), so the
    candidates are inserted in decreasing ``|score|`` order and each cut is scored
    from the one before (``cost``, a :class:`~scanlines.steps.fit.RunCost`: eq. 14,
    or in noise units); see :func:`start_sweep` and :func:`extend_sweep`.

    Returns ``ranked, accepted, sse, segments, thresholds, levels``: ``sse[m]`` and
    ``segments[m]`` describe the cut with the ``m`` best ``ranked`` candidates (those
    ``accepted`` is False for do not cut); ``levels[t]`` is the cut each tried
    threshold ``thresholds[t]`` gives.
    """
    return _core.sweep_levels(
        cost, int64s(start), int64s(end), int64s(candidates), float64s(scores), float64s(grid),
        bool(use_grid), int(max_evaluations), bool(shared),
    )  # fmt: skip


def extend_sweep(sweep: Sweep, cost: RunCost, shared: bool, done: int, upto: int) -> int:
    """Insert candidates ``done .. upto - 1`` of ``sweep`` (in place) and score each cut.

    A candidate is dropped when a part it would create is too short (Step 5: a corner
    needs at least two points on each side of it). ``shared`` cuts a run ``[a, b]`` at
    ``c`` into ``[a, c]`` and ``[c, b]`` (the corner point ends one segment and starts the
    next, as in the paper); otherwise into ``[a, c]`` and ``[c + 1, b]``. Returns
    ``upto``, the count inserted.
    """
    return _core.extend_sweep(sweep, cost, bool(shared), int(done), int(upto))


def start_sweep(cost: RunCost, start, end, candidates, scores, grid, use_grid: bool,
                max_evaluations: int) -> Sweep:  # fmt: skip
    """A :class:`Sweep` of the clusters ``[start, end]`` with no candidate inserted yet.

    ``use_grid`` tries the thresholds ``grid``; otherwise the candidates' own scores
    (every distinct segmentation, best first, at most ``max_evaluations``). Equal scores
    rank in position order.
    """
    return _core.start_sweep(
        cost, int64s(start), int64s(end), int64s(candidates), float64s(scores), float64s(grid),
        bool(use_grid), int(max_evaluations),
    )  # fmt: skip


def best_level(criterion: int, sse, segments, levels, n_points: int, sigma: float, penalty: float):
    """Index of the best tried threshold (the first on a tie) and every criterion value.

    The criterion of one segmentation: the SSE (``"sse"``), or ``SSE / sigma^2 + penalty
    ln(max(n_points, 2)) segments`` (``"bic"``); a NaN SSE counts as inf."""
    return _core.best_level(
        int(criterion), float64s(sse), int64s(segments), int64s(levels), int(n_points),
        float(sigma), float(penalty),
    )  # fmt: skip


def level_corners(ranked, accepted, level: int) -> np.ndarray:
    """Sorted positions of the accepted candidates among the ``level`` best."""
    return _core.level_corners(int64s(ranked), bools(accepted), int(level))


def split_at_farthest(x, y, moments: Moments, a, b, group, threshold: float, reference: int):
    """Each run ``[a, b]`` (of ``group``) split recursively, depth first (module docstring).

    Returns ``a, b, group`` of the final runs, each input run's parts in order
    (so sequence order for disjoint runs given in order).
    """
    return _core.split_at_farthest(
        float64s(x), float64s(y), *moments, int64s(a), int64s(b), int64s(group), float(threshold),
        int(reference),
    )  # fmt: skip


def chord_distance(x, y, a: int, b: int, p: int) -> float:
    """Distance of point ``p`` to the chord from point ``a`` to point ``b``.

    The chord is the segment between the two points: a point whose foot lies beyond an
    end is measured to that end. For a cluster that nearly closes on itself (a room seen
    all round) the chord is short and its line points anywhere; measured to the segment,
    the farthest point is the far corner, not an arbitrary point of the side opposite the
    chord.
    """
    return _core.chord_distance(float64s(x), float64s(y), a, b, p)


def sweep_decided(sweep: Sweep, cost: RunCost, shared: bool, done: int, n_points: int,
                  sigma: float, penalty: float) -> tuple[int, int]:  # fmt: skip
    """Extend ``sweep`` (from ``done`` inserted) until the ``"bic"`` choice with noise
    ``sigma`` is certain; returns ``(best level, inserted)``.

    Under ``"bic"`` the sweep (:func:`~scanlines.steps.select.start_sweep`,
    :func:`~scanlines.steps.select.extend_sweep`, :data:`SWEEP_CHUNK` candidates at a
    time) stops as soon as no lower threshold can win: the value of the cut with ``m``
    candidates is at least ``penalty ln(n) segments[m]`` (its SSE term is not negative)
    and ``segments`` never falls as thresholds fall, so once that charge alone reaches
    the best value so far no later cut can win (ties go to the first): the level is the
    full sweep's, found without inserting the rest.
    """
    return _core.sweep_decided(
        sweep, cost, bool(shared), int(done), int(n_points), float(sigma), float(penalty)
    )


def residual_tolerances(r: np.ndarray, noise: NoiseLine, floor: float) -> np.ndarray:
    """How far each return (at ranges ``r``) may lie from its segment's line: ``floor``
    (metres), or 5 times the noise sigma at its range where that is more (Gaussian noise
    puts one return in about 1.7 million farther, so on a noisy sensor the bound cuts at
    shapes, not at noise)."""
    return _core.residual_tolerances(float64s(r), tuple(noise), float(floor))


def auto_abd_lambda(step: float) -> float:
    """ABD's ``lambda`` (radians) for beams ``step`` apart.

    10 deg (Borges and Aldon's: walls up to 80 deg incidence stay one cluster), raised
    where it would bridge steps of more than :data:`MAX_BRIDGED_SHARE` of the range: on
    scans coarser than 0.67 deg (15 deg at 1 deg). There, returns on a wall near grazing
    incidence are many noise sigmas apart, so the line-continuation test keeps such walls
    whole, while the 10 deg bound would also bridge depth steps of 10 % of the range,
    which then pass for corners (``docs/decisions/breakpoints.md``). At most 90 deg
    (scans coarser than 4 deg cannot keep to the share).
    """
    return _core.auto_abd_lambda(float(step))
