"""The scan pairs repeatability compares: tolerances, registration, segment matching."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from scanlines import Scan
from scanlines.geometry.registration import (
    IDENTITY,
    IcpSettings,
    LineTarget,
    Pose,
    Registration,
    compose,
    icp,
    invert,
    line_target,
    relative_pose,
    transform_points,
)

OnProgress = Callable[[int, int], None]


@dataclass(frozen=True)
class RepeatTolerances:
    """What counts: pairs, long segments, matches (metres, radians, shares, records)."""

    min_length: float = 0.5
    alpha: float = math.radians(2.0)
    distance: float = 0.03
    distance_at: str = "overlap"
    overlap: float = 0.5
    view_overlap: float = 0.5
    min_inliers: float = 0.5
    max_gap: int = 3
    few_points: int = 5
    occlusion_margin: float = 0.2
    max_pairs: int | None = None
    strict_distance: float = 0.03
    fidelity_band: float = 0.10
    fidelity_returns: int = 5

    def to_dict(self) -> dict[str, Any]:
        """The tolerances by name, with ``alpha_deg``."""
        return asdict(self) | {"alpha_deg": math.degrees(self.alpha)}

    def caption(self) -> str:
        """One line stating the definition, for table captions."""
        return (
            f"long segments >= {self.min_length:g} m of scan i vs segments of scans "
            f"i+1..i+{self.max_gap} moved by ICP; match: angle <= "
            f"{math.degrees(self.alpha):g} deg, line distance at the shared middle <= "
            f"{100 * self.distance:g} cm, overlap / shorter >= {self.overlap:g}; pairs used: "
            f"view overlap >= {self.view_overlap:g}, ICP inliers >= {self.min_inliers:g}"
            + ("" if self.max_pairs is None else f", {self.max_pairs} spread over the log")
        )


# --------------------------------------------------------------------------- pairs


@dataclass(frozen=True)
class PairRecord:
    """One candidate pair of scans and its registration.

    Attributes
    ----------
    i, j:
        Record numbers of the two scans (``j`` later).
    initial, pose:
        Relative pose of ``j`` in ``i`` before and after ICP.
    rms, inlier_fraction, iterations, converged:
        The registration's quality (:class:`~.registration.Registration`).
    view_overlap:
        The view overlap with the refined pose.
    used:
        Whether the pair counts (view overlap and inliers at least their thresholds).
    """

    i: int
    j: int
    initial: Pose
    pose: Pose
    rms: float
    inlier_fraction: float
    iterations: int
    converged: bool
    view_overlap: float
    used: bool

    @property
    def motion(self) -> tuple[float, float]:
        """Translation (metres) and absolute rotation (radians) of the refined pose."""
        return math.hypot(self.pose[0], self.pose[1]), abs(self.pose[2])

    @property
    def correction(self) -> tuple[float, float]:
        """How far ICP moved the initial guess: translation (metres), rotation (radians)."""
        dx, dy, dt = (a - b for a, b in zip(self.pose, self.initial, strict=True))
        return math.hypot(dx, dy), abs(math.remainder(dt, 2.0 * math.pi))

    def to_dict(self) -> dict[str, Any]:
        """Flat row for CSV."""
        move, turn = self.motion
        fix, fix_turn = self.correction
        return {
            "i": self.i,
            "j": self.j,
            "x": self.pose[0],
            "y": self.pose[1],
            "theta_deg": math.degrees(self.pose[2]),
            "initial_x": self.initial[0],
            "initial_y": self.initial[1],
            "initial_theta_deg": math.degrees(self.initial[2]),
            "motion_m": move,
            "turn_deg": math.degrees(turn),
            "icp_correction_m": fix,
            "icp_correction_deg": math.degrees(fix_turn),
            "icp_rms_m": self.rms,
            "icp_inliers": self.inlier_fraction,
            "icp_iterations": self.iterations,
            "icp_converged": self.converged,
            "view_overlap": self.view_overlap,
            "used": self.used,
        }


def _share_in_view(points: np.ndarray, scan: Scan, margin: float) -> float:
    """Share of ``points`` (in ``scan``'s frame) inside its view and not hidden behind it."""
    if len(points) == 0:
        return 0.0
    n, step = len(scan), abs(scan.angle_increment)
    r = np.hypot(points[:, 0], points[:, 1])
    # Beam coordinate of each bearing, counted from beam 0 the way the beams turn.
    turn = (np.arctan2(points[:, 1], points[:, 0]) - scan.angle_min) * np.sign(scan.angle_increment)
    k = np.mod(turn, 2.0 * math.pi) / step
    if scan.full_circle:
        inside = np.ones(len(points), dtype=bool)
        nearest = np.rint(k).astype(np.intp) % n
    else:
        inside = (k <= n - 0.5) | (k >= 2.0 * math.pi / step - 0.5)
        nearest = np.where(k <= n - 0.5, np.rint(k), 0).astype(np.intp)
    inside &= (r >= scan.range_min) & (r <= scan.range_max)
    measured = np.where(scan.valid, scan.ranges, -np.inf)
    farthest = np.max(np.stack([measured[(nearest + d) % n] for d in (-1, 0, 1)], axis=1), axis=1)
    hidden = np.isfinite(farthest) & (r > farthest + margin)
    return float(np.count_nonzero(inside & ~hidden) / len(points))


def view_overlap(scan_i: Scan, scan_j: Scan, pose: Sequence[float], margin: float = 0.2) -> float:
    """The smaller share of either scan's returns that lie in the other's view.

    ``pose`` is ``j``'s frame in ``i``'s. A return lies in a scan's view when it is inside
    the field of view and the range limits and not more than ``margin`` behind the
    farthest of the three nearest beams' returns.
    """
    pj = transform_points(scan_j.points[scan_j.valid], pose)
    pi = transform_points(scan_i.points[scan_i.valid], invert(pose))
    return min(_share_in_view(pj, scan_i, margin), _share_in_view(pi, scan_j, margin))


def _better(a: Registration, b: Registration) -> Registration:
    if a.n_inliers != b.n_inliers:
        return a if a.n_inliers > b.n_inliers else b
    return a if (a.rms if math.isfinite(a.rms) else math.inf) <= b.rms else b


class _Registrar:
    """Registers pairs of positions in ``scans`` on demand, each once.

    With the log's poses, from their relative pose. Without: ``(a, a + 1)`` from the
    identity and from the refined pose of ``(a - 1, a)`` when that one is registered and
    good (constant velocity), keeping the fit with more inliers; ``(a, a + k)`` from the
    chain of the refined consecutive poses (registered first when they are not yet).
    """

    def __init__(self, scans: Sequence[tuple[int, Scan]], tol: RepeatTolerances, settings):
        self.scans, self.tol, self.settings = scans, tol, settings
        self.with_poses = all(scan.pose is not None for _, scan in scans)
        self.fits: dict[tuple[int, int], Registration] = {}
        self._targets: dict[int, LineTarget] = {}

    def _target(self, a: int) -> LineTarget:
        if a not in self._targets:
            self._targets[a] = line_target(self.scans[a][1], self.settings)
        return self._targets[a]

    def fit(self, a: int, b: int) -> Registration:
        if (a, b) in self.fits:
            return self.fits[(a, b)]
        (_, scan_i), (_, scan_j) = self.scans[a], self.scans[b]
        source, target = scan_j.points[scan_j.valid], self._target(a)
        if self.with_poses:
            found = icp(source, target, relative_pose(scan_i.pose, scan_j.pose), self.settings)
        elif b == a + 1:
            found = icp(source, target, IDENTITY, self.settings)
            before = self.fits.get((a - 1, a))
            if before is not None and before.inlier_fraction >= self.tol.min_inliers:
                found = _better(found, icp(source, target, before.pose, self.settings))
        else:
            chain = IDENTITY
            for step in range(a, b):
                chain = compose(chain, self.fit(step, step + 1).pose)
            found = icp(source, target, chain, self.settings)
        self.fits[(a, b)] = found
        return found

    def record(self, a: int, b: int) -> PairRecord:
        fit = self.fit(a, b)
        (i, scan_i), (j, scan_j) = self.scans[a], self.scans[b]
        overlap = view_overlap(scan_i, scan_j, fit.pose, self.tol.occlusion_margin)
        used = overlap >= self.tol.view_overlap and fit.inlier_fraction >= self.tol.min_inliers
        return PairRecord(
            i,
            j,
            fit.initial,
            fit.pose,
            fit.rms,
            fit.inlier_fraction,
            fit.iterations,
            fit.converged,
            overlap,
            used,
        )


def register_pairs(
    scans: Sequence[tuple[int, Scan]],
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_pair: OnProgress | None = None,
) -> tuple[tuple[PairRecord, ...], str]:
    """The pairs of ``scans`` (``(record, scan)`` in log order) that were registered.

    Without ``tol.max_pairs``: every candidate pair (:func:`candidate_pairs`), each
    marked ``used`` or not. With it: the candidates are cut into ``max_pairs`` slots of
    consecutive pairs (:func:`pair_slots`), and each slot's candidates are registered in
    turn until one is used; the tried pairs are returned, so that ``max_pairs`` pairs
    (fewer only where a whole slot has none) are used, spread evenly over the log.
    Also returns the pose source: ``"log poses + ICP"`` when every scan has a pose,
    else ``"ICP alone"`` (see :mod:`scanlines.evaluation.repeatability`).
    """
    tol = tol or RepeatTolerances()
    settings = settings or IcpSettings()
    registrar = _Registrar(scans, tol, settings)
    candidates = candidate_pairs(scans, tol)
    tried: list[PairRecord] = []
    if tol.max_pairs is None or len(candidates) <= tol.max_pairs:
        # The consecutive pairs first, so that the longer ones chain refined poses.
        ordered = sorted(candidates, key=lambda ab: (ab[1] - ab[0], ab))
        for done, (a, b) in enumerate(ordered):
            tried.append(registrar.record(a, b))
            if on_pair is not None:
                on_pair(done + 1, len(ordered))
    else:
        slots = pair_slots(candidates, tol.max_pairs, tol.max_gap)
        for done, slot in enumerate(slots):
            for a, b in slot:
                tried.append(registrar.record(a, b))
                if tried[-1].used:
                    break
            if on_pair is not None:
                on_pair(done + 1, len(slots))
    tried.sort(key=lambda p: (p.i, p.j))
    return tuple(tried), "log poses + ICP" if registrar.with_poses else "ICP alone"


def candidate_pairs(scans: Sequence[tuple[int, Scan]], tol: RepeatTolerances) -> list:
    """Positions ``(a, b)`` of every pair 1 to ``max_gap`` records apart, in log order."""
    return [
        (a, b)
        for a in range(len(scans))
        for b in range(a + 1, min(a + 1 + tol.max_gap, len(scans)))
        if 1 <= scans[b][0] - scans[a][0] <= tol.max_gap
    ]


def pair_slots(candidates: Sequence[tuple[int, int]], slots: int, max_gap: int = 3) -> list:
    """``candidates`` (in log order) cut into ``slots`` runs of consecutive pairs, so that
    one pair of each spreads the pairs evenly over the log; in each run the pairs whose
    gap is the slot's turn (cycling through 1 .. ``max_gap``) come first, then the
    others, each in log order."""
    cut = [k * len(candidates) // slots for k in range(slots + 1)]
    out = []
    for k in range(slots):
        run = list(candidates[cut[k] : cut[k + 1]])
        turn = k % max_gap
        run.sort(key=lambda ab: ((ab[1] - ab[0] - 1 - turn) % max_gap, ab))
        out.append(run)
    return out


# --------------------------------------------------------------------------- matching


def match_segments(
    ends_i: np.ndarray, ends_j: np.ndarray, tol: RepeatTolerances | None = None
) -> np.ndarray:
    """``M x K`` booleans: segment ``m`` of ``i`` matches segment ``k`` of ``j``.

    ``ends_*`` are ``N x 4`` arrays ``start x, start y, end x, end y``, both in ``i``'s
    frame. The three conditions are those of :mod:`scanlines.evaluation.repeatability`.
    """
    tol = tol or RepeatTolerances()
    ends_i = np.asarray(ends_i, dtype=np.float64).reshape(-1, 4)
    ends_j = np.asarray(ends_j, dtype=np.float64).reshape(-1, 4)
    if len(ends_i) == 0 or len(ends_j) == 0:
        return np.zeros((len(ends_i), len(ends_j)), dtype=bool)
    a = ends_i[:, None, 0:2]
    d_i = ends_i[:, 2:4] - ends_i[:, 0:2]
    length = np.hypot(d_i[:, 0], d_i[:, 1])[:, None]
    u = (d_i / np.maximum(length, 1e-12))[:, None, :]
    normal = np.concatenate((-u[..., 1:2], u[..., 0:1]), axis=-1)
    s, e = ends_j[None, :, 0:2], ends_j[None, :, 2:4]
    d_j = ends_j[:, 2:4] - ends_j[:, 0:2]
    u_j = d_j / np.maximum(np.hypot(d_j[:, 0], d_j[:, 1]), 1e-12)[:, None]
    cos = np.abs(np.sum(u * u_j[None, :, :], axis=-1))
    angle_ok = cos >= math.cos(tol.alpha)
    ps = np.sum((s - a) * u, axis=-1)
    pe = np.sum((e - a) * u, axis=-1)
    lo, hi = np.minimum(ps, pe), np.maximum(ps, pe)
    common_lo, common_hi = np.maximum(lo, 0.0), np.minimum(hi, length)
    common = np.maximum(common_hi - common_lo, 0.0)
    shorter = np.minimum(length, hi - lo)
    with np.errstate(invalid="ignore", divide="ignore"):
        overlap_ok = (shorter > 0) & (common / shorter >= tol.overlap)
        middle = (common_lo + common_hi) / 2.0
        # The point of t above `middle`: interpolate the signed distances of its ends.
        ds = np.sum((s - a) * normal, axis=-1)
        de = np.sum((e - a) * normal, axis=-1)
        along = np.where(pe != ps, (middle - ps) / (pe - ps), 0.5)
        distance = np.abs(ds + along * (de - ds))
    if tol.distance_at == "origin":  # Hesse form: |drho| of the two lines in i's frame
        rho_i = np.sum(a * normal, axis=-1)
        sign = np.where(np.sum(normal * np.stack((-u_j[:, 1], u_j[:, 0]), axis=-1), -1) < 0, -1, 1)
        n_j = sign[..., None] * np.stack((-u_j[:, 1], u_j[:, 0]), axis=-1)[None, :, :]
        distance = np.abs(np.sum(s * n_j, axis=-1) - rho_i)
    return angle_ok & overlap_ok & (distance <= tol.distance)


def _moved(ends: np.ndarray, pose: Pose) -> np.ndarray:
    if len(ends) == 0:
        return ends
    return np.column_stack(
        (transform_points(ends[:, 0:2], pose), transform_points(ends[:, 2:4], pose))
    )
