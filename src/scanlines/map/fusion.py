"""Association and fusion of world-frame segments into map lines (streaming, bounded memory).

A segment ``(rho, alpha)`` with covariance ``P_s`` joins the map line ``(rho_m, alpha_m, P_m)``
it agrees with: the Mahalanobis distance of the difference under ``P_s + P_m`` is within the
chi-square gate, and along the line the segment overlaps the line's extent or leaves a gap of
at most ``max_gap``. Of the lines that pass, the nearest (Mahalanobis) wins. The line's
estimate becomes the information-weighted mean of the two, its extent the union of both.
A segment that joins none starts a line. Lines seen by fewer than ``min_scans`` scans are
clutter: dropped at the end, and retired on the way once ``retire_after`` scans have passed
without seeing them again, so memory follows the size of the place, not the log's length.
Lines that come to agree with each other (a wall first seen in two pieces) are merged every
``merge_every`` scans.

The covariance of a segment moved into the world includes the pose's own uncertainty
(``pose_sigma_xy``, ``pose_sigma_theta``): without it, millimetre range noise makes every
pose error of a corrected log look like a different wall.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from scanlines.extraction import ALPHA, END_X, END_Y, RHO, START_X, START_Y, Extraction

__all__ = ["FusionSettings", "LineMap", "MapLines"]

_CHI2_2DOF = {0.95: 5.991, 0.99: 9.210, 0.999: 13.816}


@dataclass(frozen=True)
class FusionSettings:
    """The constants of association and fusion (metres, radians, scans)."""

    gate: float = 0.99
    max_gap: float = 0.5
    min_scans: int = 3
    min_points: int = 5
    pose_sigma_xy: float = 0.02
    pose_sigma_theta: float = math.radians(0.5)
    model_sigma_rho: float = 0.0
    model_sigma_alpha: float = 0.0
    retire_after: int = 300
    merge_every: int = 50

    def __post_init__(self) -> None:
        from scanlines.errors import ParameterError

        if self.gate not in _CHI2_2DOF:
            raise ParameterError(f"gate must be one of {sorted(_CHI2_2DOF)}, got {self.gate}")
        checks = {
            "max_gap": self.max_gap >= 0,
            "min_scans": self.min_scans >= 1,
            "min_points": self.min_points >= 2,
            "pose_sigma_xy": self.pose_sigma_xy >= 0,
            "pose_sigma_theta": self.pose_sigma_theta >= 0,
            "model_sigma_rho": self.model_sigma_rho >= 0,
            "model_sigma_alpha": self.model_sigma_alpha >= 0,
            "retire_after": self.retire_after >= 1,
            "merge_every": self.merge_every >= 1,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not ok or not math.isfinite(value):
                raise ParameterError(f"fusion setting {name} out of range: {value!r}")

    @property
    def chi2(self) -> float:
        return _CHI2_2DOF[self.gate]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class MapLines:
    """The lines of a map, as arrays (one row per line).

    ``rho, alpha``: Hesse normal form in the world frame (``rho >= 0``); ``covariances``:
    ``L x 2 x 2`` of ``(rho, alpha)``; ``start, end``: ``L x 2`` endpoints of the extent;
    ``scans``, ``returns``: support; ``first_scan``, ``last_scan``: log indices of the first
    and last scan that saw the line; ``segments``: segments fused into it.
    """

    rho: np.ndarray
    alpha: np.ndarray
    covariances: np.ndarray
    start: np.ndarray
    end: np.ndarray
    scans: np.ndarray
    returns: np.ndarray
    first_scan: np.ndarray
    last_scan: np.ndarray
    segments: np.ndarray

    def __len__(self) -> int:
        return len(self.rho)

    @property
    def lengths(self) -> np.ndarray:
        return np.hypot(*(self.end - self.start).T) if len(self) else np.zeros(0)


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


class LineMap:
    """A map of lines built one scan at a time: :meth:`add` a scan's world-frame features,
    :meth:`lines` for the map (clutter dropped)."""

    def __init__(self, settings: FusionSettings | None = None) -> None:
        self.settings = settings or FusionSettings()
        self._n = 0
        self._grow(64)
        self.segments_seen = 0
        self.segments_fused = 0
        self.retired = 0
        self.scans_added = 0
        self._since_merge = 0

    # -- storage ---------------------------------------------------------------------------

    def _grow(self, capacity: int) -> None:
        def grown(old: np.ndarray | None, shape: tuple[int, ...], dtype) -> np.ndarray:
            new = np.zeros((capacity, *shape), dtype=dtype)
            if old is not None:
                new[: self._n] = old[: self._n]
            return new

        had = getattr(self, "_rho", None) is not None
        get = (lambda name: getattr(self, name)) if had else (lambda name: None)
        self._rho = grown(get("_rho"), (), np.float64)
        self._alpha = grown(get("_alpha"), (), np.float64)
        self._cov = grown(get("_cov"), (2, 2), np.float64)
        self._t = grown(get("_t"), (2,), np.float64)  # extent along the line's tangent
        self._scans = grown(get("_scans"), (), np.int64)
        self._returns = grown(get("_returns"), (), np.int64)
        self._first = grown(get("_first"), (), np.int64)
        self._last = grown(get("_last"), (), np.int64)
        self._fused = grown(get("_fused"), (), np.int64)

    def __len__(self) -> int:
        return self._n

    # -- one scan --------------------------------------------------------------------------

    def add(self, world: Extraction, scan_index: int, pose: tuple[float, float, float]) -> None:
        """Fuse the segments of one scan, already in the world frame (``to_world``), whose
        sensor stood at ``pose``; ``scan_index`` is the scan's index in the log."""
        self.scans_added += 1
        keep = np.asarray(world.n_points) >= self.settings.min_points
        lines = np.asarray(world.lines)[keep]
        covariances = np.asarray(world.covariances)[keep] + self._pose_noise(lines, pose)
        n_points = np.asarray(world.n_points)[keep]
        self.segments_seen += len(lines)
        if len(lines):
            targets = self._associate(lines, covariances)
            for k, target in enumerate(targets):
                if target < 0:
                    self._append(lines[k], covariances[k], int(n_points[k]), scan_index)
                else:
                    self._fuse(int(target), lines[k], covariances[k], int(n_points[k]), scan_index)
        self._since_merge += 1
        if self._since_merge >= self.settings.merge_every:
            self._since_merge = 0
            self.merge_agreeing()
            self._retire(scan_index)

    def _pose_noise(self, lines: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
        """``(rho, alpha)`` covariance that the pose's uncertainty adds to each line."""
        x, y, _ = pose
        a = lines[:, ALPHA]
        # A turn of the pose turns the line about the sensor at (x, y): rho moves by the
        # sensor's offset along the line, -x sin(a) + y cos(a).
        jac = np.zeros((len(lines), 2, 3))
        jac[:, 0, 0] = np.cos(a)
        jac[:, 0, 1] = np.sin(a)
        jac[:, 0, 2] = -x * np.sin(a) + y * np.cos(a)
        jac[:, 1, 2] = 1.0
        xy, theta = self.settings.pose_sigma_xy, self.settings.pose_sigma_theta
        sigma = np.diag([xy**2, xy**2, theta**2])
        return jac @ sigma @ jac.transpose(0, 2, 1)

    def _associate(self, lines: np.ndarray, covariances: np.ndarray) -> np.ndarray:
        """Index of the map line each segment joins, ``-1`` for none."""
        n = self._n
        targets = np.full(len(lines), -1, dtype=np.int64)
        if n == 0:
            return targets
        score = self._agreement(
            lines[:, RHO], lines[:, ALPHA], covariances, _ends_of(lines),
            self._rho[:n], self._alpha[:n], self._cov[:n], self._t[:n],
        )  # fmt: skip
        best = np.argmin(score, axis=1)
        found = np.isfinite(score[np.arange(len(lines)), best])
        targets[found] = best[found]
        return targets

    def _agreement(self, rho, alpha, cov, ends, m_rho, m_alpha, m_cov, m_t) -> np.ndarray:
        """``S x L`` Mahalanobis distances of segments to lines, ``inf`` where a gate fails."""
        d_alpha = _wrap(alpha[:, None] - m_alpha[None, :])
        flip = np.abs(d_alpha) > math.pi / 2
        sign = np.where(flip, -1.0, 1.0)
        d_rho = sign * rho[:, None] - m_rho[None, :]
        d_alpha = _wrap(d_alpha - np.where(flip, math.pi, 0.0))
        s_rr = cov[:, None, 0, 0] + m_cov[None, :, 0, 0] + self.settings.model_sigma_rho**2
        s_aa = cov[:, None, 1, 1] + m_cov[None, :, 1, 1] + self.settings.model_sigma_alpha**2
        s_ra = sign * cov[:, None, 0, 1] + m_cov[None, :, 0, 1]
        det = s_rr * s_aa - s_ra**2
        with np.errstate(divide="ignore", invalid="ignore"):
            d2 = (s_aa * d_rho**2 - 2 * s_ra * d_rho * d_alpha + s_rr * d_alpha**2) / det
        d2 = np.where(det > 0, d2, np.inf)
        tangent = np.stack((-np.sin(m_alpha), np.cos(m_alpha)), axis=-1)  # L x 2
        along = np.einsum("sek,lk->sle", ends, tangent)  # S x L x 2
        lo, hi = along.min(axis=2), along.max(axis=2)
        gap = np.maximum(lo - m_t[None, :, 1], m_t[None, :, 0] - hi)
        ok = (d2 <= self.settings.chi2) & (gap <= self.settings.max_gap)
        return np.where(ok, d2, np.inf)

    def _append(self, line, cov, n_points: int, scan_index: int) -> None:
        if self._n == len(self._rho):
            self._grow(2 * len(self._rho))
        k = self._n
        self._n += 1
        self._rho[k], self._alpha[k], self._cov[k] = line[RHO], line[ALPHA], cov
        self._t[k] = _extent(line[RHO], line[ALPHA], _ends_of(line[None])[0])
        self._scans[k], self._returns[k], self._fused[k] = 1, n_points, 1
        self._first[k] = self._last[k] = scan_index

    def _fuse(self, k: int, line, cov, n_points: int, scan_index: int) -> None:
        rho, alpha = float(line[RHO]), float(line[ALPHA])
        if abs(_wrap(alpha - self._alpha[k])) > math.pi / 2:  # the same line, other normal
            rho, alpha = -rho, float(_wrap(alpha + math.pi))
            cov = cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
        ends = np.vstack((self._ends(k), _ends_of(line[None])[0]))
        self._combine(k, rho, alpha, cov)
        self._t[k] = _extent(self._rho[k], self._alpha[k], ends)
        if self._last[k] != scan_index:
            self._scans[k] += 1
        self._returns[k] += n_points
        self._fused[k] += 1
        self._first[k] = min(self._first[k], scan_index)
        self._last[k] = max(self._last[k], scan_index)
        self.segments_fused += 1

    def _combine(self, k: int, rho: float, alpha: float, cov: np.ndarray) -> None:
        """Information-weighted mean of line ``k`` and ``(rho, alpha, cov)``."""
        info_m = np.linalg.inv(self._cov[k])
        info_s = np.linalg.inv(cov)
        fused_cov = np.linalg.inv(info_m + info_s)
        mean_m = np.array([self._rho[k], self._alpha[k]])
        mean_s = np.array([rho, self._alpha[k] + _wrap(alpha - self._alpha[k])])
        mean = fused_cov @ (info_m @ mean_m + info_s @ mean_s)
        if mean[0] < 0:
            mean = np.array([-mean[0], mean[1] + math.pi])
            fused_cov = fused_cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self._rho[k], self._alpha[k] = mean[0], float(_wrap(mean[1]))
        self._cov[k] = (fused_cov + fused_cov.T) / 2

    def _ends(self, k: int) -> np.ndarray:
        return _points_at(self._rho[k], self._alpha[k], self._t[k])

    # -- the map as a whole ----------------------------------------------------------------

    def merge_agreeing(self) -> int:
        """Merge every pair of lines that agree (the gates of association); how many went."""
        merged = 0
        for _ in range(4):  # each pass merges disjoint pairs; a few passes settle chains
            n = self._n
            if n < 2:
                break
            ends = np.stack([self._ends(k) for k in range(n)])
            score = self._agreement(
                self._rho[:n], self._alpha[:n], self._cov[:n], ends,
                self._rho[:n], self._alpha[:n], self._cov[:n], self._t[:n],
            )  # fmt: skip
            score[np.tril_indices(n)] = np.inf
            pairs = np.argwhere(np.isfinite(score))
            if not len(pairs):
                break
            order = np.argsort(score[pairs[:, 0], pairs[:, 1]])
            used = np.zeros(n, dtype=bool)
            gone = []
            for i, j in pairs[order]:
                if used[i] or used[j]:
                    continue
                used[i] = used[j] = True
                self._absorb(int(i), int(j))
                gone.append(int(j))
            self._remove(np.array(gone, dtype=np.int64))
            merged += len(gone)
        return merged

    def _absorb(self, i: int, j: int) -> None:
        """Line ``j`` fused into line ``i`` (``j`` is removed by the caller)."""
        ends = np.vstack((self._ends(i), self._ends(j)))
        rho, alpha, cov = self._rho[j], self._alpha[j], self._cov[j]
        if abs(_wrap(alpha - self._alpha[i])) > math.pi / 2:
            rho, alpha = -rho, float(_wrap(alpha + math.pi))
            cov = cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self._combine(i, rho, alpha, cov)
        self._t[i] = _extent(self._rho[i], self._alpha[i], ends)
        self._scans[i] += self._scans[j]  # an upper bound: both may have seen one scan
        self._returns[i] += self._returns[j]
        self._fused[i] += self._fused[j]
        self._first[i] = min(self._first[i], self._first[j])
        self._last[i] = max(self._last[i], self._last[j])

    def _remove(self, rows: np.ndarray) -> None:
        if not len(rows):
            return
        keep = np.ones(self._n, dtype=bool)
        keep[rows] = False
        n = int(keep.sum())
        for name in ("_rho", "_alpha", "_cov", "_t", "_scans", "_returns", "_first", "_last",
                     "_fused"):  # fmt: skip
            array = getattr(self, name)
            array[:n] = array[: self._n][keep]
        self._n = n

    def _retire(self, scan_index: int) -> None:
        """Drop lines too weakly supported to be kept that have not been seen for long."""
        n = self._n
        stale = (self._scans[:n] < self.settings.min_scans) & (
            scan_index - self._last[:n] > self.settings.retire_after
        )
        self.retired += int(stale.sum())
        self._remove(np.flatnonzero(stale))

    def lines(self, min_scans: int | None = None) -> MapLines:
        """The map: lines seen by at least ``min_scans`` scans (default: the settings')."""
        self.merge_agreeing()
        n = self._n
        floor = self.settings.min_scans if min_scans is None else min_scans
        keep = np.flatnonzero(self._scans[:n] >= floor)
        ends = np.stack([self._ends(k) for k in keep]) if len(keep) else np.zeros((0, 2, 2))
        return MapLines(
            rho=self._rho[keep].copy(),
            alpha=self._alpha[keep].copy(),
            covariances=self._cov[keep].copy(),
            start=ends[:, 0].copy(),
            end=ends[:, 1].copy(),
            scans=self._scans[keep].copy(),
            returns=self._returns[keep].copy(),
            first_scan=self._first[keep].copy(),
            last_scan=self._last[keep].copy(),
            segments=self._fused[keep].copy(),
        )


def _ends_of(lines: np.ndarray) -> np.ndarray:
    """``S x 2 x 2`` endpoints (start, end) of world-frame segment rows."""
    return np.stack((lines[:, [START_X, START_Y]], lines[:, [END_X, END_Y]]), axis=1).astype(
        np.float64
    )


def _extent(rho: float, alpha: float, points: np.ndarray) -> np.ndarray:
    """``[t_min, t_max]`` of ``points`` along the line's tangent."""
    along = points @ np.array([-math.sin(alpha), math.cos(alpha)])
    return np.array([along.min(), along.max()])


def _points_at(rho: float, alpha: float, t: np.ndarray) -> np.ndarray:
    """Points of the line at tangent coordinates ``t`` (``2 x 2``)."""
    normal = np.array([math.cos(alpha), math.sin(alpha)])
    tangent = np.array([-math.sin(alpha), math.cos(alpha)])
    return rho * normal[None, :] + np.asarray(t)[:, None] * tangent[None, :]
