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
pose error of a corrected log look like a different wall. And since the pose errors of
neighbouring scans are alike rather than independent, a line fused from many views is not
known better than the poses that placed it: ``model_sigma_rho``, ``model_sigma_alpha``
(by default the pose's own sigmas) are added to every gate's covariance, so two pieces of
one wall, each fused from many scans, still agree.

A line keeps the side its returns came from (:data:`FRONT`: the side its normal
``(cos alpha, sin alpha)`` points to, where ``x cos(alpha) + y sin(alpha) > rho``;
:data:`BACK`: the other; both where both were seen): the sensor's side of each segment it
fused. The two faces of a thin wall are two lines, each seen from its own side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from scanlines.extraction import ALPHA, END_X, END_Y, RHO, START_X, START_Y, Extraction
from scanlines.map.frame import LocalFrame, MapError, check_segments
from scanlines.map.grid import box_pairs, boxes_of
from scanlines.params import (
    MAX_COUNT,
    MAX_METRES,
    MAX_SCANS,
    KernelField,
    Param,
    choice,
    integer,
    number,
)
from scanlines.params.tables import Groups, SettingsTable

__all__ = ["BACK", "BOTH", "FRONT", "FusionSettings", "LineMap", "MapLines", "side_of"]

#: The sides of a line a sensor saw it from (bits): its normal's side, the other, both.
FRONT, BACK, BOTH = 1, 2, 3

_CHI2_2DOF = {0.95: 5.991, 0.99: 9.210, 0.999: 13.816}


_METRES, _RADIANS = number(low=0.0, high=MAX_METRES), number(low=0.0, high=math.pi)
_SCANS, _POINTS = integer(1, MAX_SCANS), integer(2, MAX_COUNT)


class FusionSettings(SettingsTable):
    """The constants of association and fusion (metres, radians, scans)."""

    groups: ClassVar[Groups] = {
        "association": {
            "gate": Param(
                0.99,
                choice(*_CHI2_2DOF),
                "probability of the chi-square gate (2 dof) a segment and its line pass",
                kernel=(KernelField("chi2", _CHI2_2DOF.__getitem__),),
            ),
            "max_gap": Param(0.5, _METRES, "largest gap along a line to a segment it fuses (m)"),
        },
        "support": {
            "min_scans": Param(3, _SCANS, "lines seen by fewer scans are clutter, dropped"),
            "min_points": Param(5, _POINTS, "segments of fewer returns are not fused"),
        },
        "uncertainty": {
            "pose_sigma_xy": Param(0.02, _METRES, "a pose's position sigma, its segments' too (m)"),
            "pose_sigma_theta": Param(math.radians(0.5), _RADIANS, "a pose's heading sigma (rad)"),
            "model_sigma_rho": Param(0.02, _METRES, "sigma of rho added to every gate (m)"),
            "model_sigma_alpha": Param(
                math.radians(0.5), _RADIANS, "sigma of alpha added to every gate (rad)"
            ),
        },
        "upkeep": {
            "retire_after": Param(300, _SCANS, "clutter unseen for this many scans is retired"),
            "merge_every": Param(50, _SCANS, "scans between merges of lines that came to agree"),
        },
    }

    @property
    def chi2(self) -> float:
        return _CHI2_2DOF[self.gate]


@dataclass(frozen=True)
class MapLines:
    """The lines of a map, as arrays (one row per line), in the map's local frame.

    ``origin``: where the local frame's origin is in the world (:mod:`scanlines.map.frame`;
    a point ``p`` of the local frame is ``p + origin`` in the world); ``rho, alpha``: Hesse
    normal form in the local frame (``rho >= 0``); ``covariances``: ``L x 2 x 2`` of
    ``(rho, alpha)``; ``start, end``: ``L x 2`` endpoints of the extent in the local frame
    (:attr:`world_start`, :attr:`world_end` in the world); ``scans``, ``returns``: support;
    ``first_scan``, ``last_scan``: log indices of the first and last scan that saw the line;
    ``segments``: segments fused into it; ``sides``: the sides it was seen from
    (:data:`FRONT`, :data:`BACK` or :data:`BOTH`; ``None``: not known, both).
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
    origin: tuple[float, float] = (0.0, 0.0)
    sides: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.rho)

    @property
    def world_start(self) -> np.ndarray:
        return self.start + np.array(self.origin, dtype=np.float64)

    @property
    def world_end(self) -> np.ndarray:
        return self.end + np.array(self.origin, dtype=np.float64)

    def world_hesse(self) -> tuple[np.ndarray, np.ndarray]:
        """``rho, alpha`` of each line in the world frame (``rho >= 0``). Far from the
        world's origin they are ill-conditioned (``rho`` as large as the coordinates): the
        map keeps its lines in the local frame."""
        x0, y0 = self.origin
        rho = self.rho + x0 * np.cos(self.alpha) + y0 * np.sin(self.alpha)
        flip = rho < 0
        return np.abs(rho), np.where(flip, _wrap(self.alpha + math.pi), self.alpha)

    @property
    def lengths(self) -> np.ndarray:
        return np.hypot(*(self.end - self.start).T) if len(self) else np.zeros(0)


def side_of(rho, alpha, x: float, y: float):
    """The side (:data:`FRONT` or :data:`BACK`) of lines ``(rho, alpha)`` a sensor at
    ``(x, y)`` sees them from."""
    offset = np.cos(alpha) * x + np.sin(alpha) * y - rho
    return np.where(offset > 0, FRONT, BACK).astype(np.int8)


def _swap_sides(sides):
    """The sides of a line whose normal was turned round."""
    return ((sides & FRONT) << 1) | ((sides & BACK) >> 1)


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


class LineMap:
    """A map of lines built one scan at a time: :meth:`add` a scan's features in the map's
    frame, :meth:`lines` for the map (clutter dropped).

    ``frame``: the map's local frame (:class:`~scanlines.map.frame.LocalFrame`); the
    features and poses given to :meth:`add` are in it. By default the world's own frame;
    :func:`~scanlines.map.build_map` sets it from the first pose.
    """

    def __init__(self, settings: FusionSettings | None = None, frame: LocalFrame | None = None):
        self.settings = settings or FusionSettings()
        self.frame = frame or LocalFrame()
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
        self._box = grown(get("_box"), (4,), np.float64)  # x_min, y_min, x_max, y_max
        self._sides = grown(get("_sides"), (), np.int8)

    def __len__(self) -> int:
        return self._n

    # -- one scan --------------------------------------------------------------------------

    def add(self, world: Extraction, scan_index: int, pose: tuple[float, float, float]) -> None:
        """Fuse the segments of one scan, already in the map's frame (``to_world`` by the
        pose in that frame), whose sensor stood at ``pose`` (in that frame); ``scan_index``
        is the scan's index in the log.

        Raises
        ------
        MapError
            If a segment is not finite or lies beyond
            :data:`~scanlines.map.frame.MAX_EXTENT` from the frame's origin.
        """
        self.scans_added += 1
        keep = np.asarray(world.n_points) >= self.settings.min_points
        lines = np.asarray(world.lines)[keep]
        check_segments(lines[:, [START_X, START_Y, END_X, END_Y]], f"scan {scan_index}")
        if not np.isfinite(lines[:, [RHO, ALPHA]]).all():
            raise MapError(f"scan {scan_index}: a segment's line is not finite")
        covariances = np.asarray(world.covariances)[keep] + self._pose_noise(lines, pose)
        n_points = np.asarray(world.n_points)[keep]
        sides = side_of(lines[:, RHO], lines[:, ALPHA], pose[0], pose[1])
        self.segments_seen += len(lines)
        if len(lines):
            targets = self._associate(lines, covariances)
            for k, target in enumerate(targets):
                seen = (int(n_points[k]), scan_index, int(sides[k]))
                if target < 0:
                    self._append(lines[k], covariances[k], *seen)
                else:
                    self._fuse(int(target), lines[k], covariances[k], *seen)
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
        ends = _ends_of(lines)
        seg, line = box_pairs(boxes_of(ends, self.settings.max_gap), self._box[:n])
        if not len(seg):
            return targets
        d2 = self._agreement(
            lines[seg, RHO], lines[seg, ALPHA], covariances[seg], ends[seg],
            self._rho[line], self._alpha[line], self._cov[line], self._t[line],
        )  # fmt: skip
        passed = np.isfinite(d2)
        seg, line, d2 = seg[passed], line[passed], d2[passed]
        order = np.lexsort((d2, seg))  # by segment, nearest first
        seg, line = seg[order], line[order]
        first = np.ones(len(seg), dtype=bool)
        first[1:] = seg[1:] != seg[:-1]
        targets[seg[first]] = line[first]
        return targets

    def _agreement(self, rho, alpha, cov, ends, m_rho, m_alpha, m_cov, m_t) -> np.ndarray:
        """Mahalanobis distances of segments to lines, pair by pair (``inf`` where a gate
        fails): ``rho, alpha`` (P), ``cov`` (P x 2 x 2), ``ends`` (P x 2 x 2) of the segments
        against ``m_rho, m_alpha, m_cov, m_t`` (extent along the tangent, P x 2) of the lines."""
        d_alpha = _wrap(alpha - m_alpha)
        flip = np.abs(d_alpha) > math.pi / 2
        sign = np.where(flip, -1.0, 1.0)
        d_rho = sign * rho - m_rho
        d_alpha = _wrap(d_alpha - np.where(flip, math.pi, 0.0))
        s_rr = cov[:, 0, 0] + m_cov[:, 0, 0] + self.settings.model_sigma_rho**2
        s_aa = cov[:, 1, 1] + m_cov[:, 1, 1] + self.settings.model_sigma_alpha**2
        s_ra = sign * cov[:, 0, 1] + m_cov[:, 0, 1]
        det = s_rr * s_aa - s_ra**2
        with np.errstate(divide="ignore", invalid="ignore"):
            d2 = (s_aa * d_rho**2 - 2 * s_ra * d_rho * d_alpha + s_rr * d_alpha**2) / det
        d2 = np.where(det > 0, d2, np.inf)
        tangent = np.stack((-np.sin(m_alpha), np.cos(m_alpha)), axis=-1)  # P x 2
        along = np.einsum("pek,pk->pe", ends, tangent)  # P x 2
        lo, hi = along.min(axis=1), along.max(axis=1)
        gap = np.maximum(lo - m_t[:, 1], m_t[:, 0] - hi)
        ok = (d2 <= self.settings.chi2) & (gap <= self.settings.max_gap)
        return np.where(ok, d2, np.inf)

    def _append(self, line, cov, n_points: int, scan_index: int, side: int) -> None:
        if self._n == len(self._rho):
            self._grow(2 * len(self._rho))
        k = self._n
        self._n += 1
        self._rho[k], self._alpha[k], self._cov[k] = line[RHO], line[ALPHA], cov
        self._t[k] = _extent(line[RHO], line[ALPHA], _ends_of(line[None])[0])
        self._box[k] = boxes_of(self._ends(k)[None], 0.0)[0]
        self._scans[k], self._returns[k], self._fused[k] = 1, n_points, 1
        self._first[k] = self._last[k] = scan_index
        self._sides[k] = side

    def _fuse(self, k: int, line, cov, n_points: int, scan_index: int, side: int) -> None:
        rho, alpha = float(line[RHO]), float(line[ALPHA])
        if abs(_wrap(alpha - self._alpha[k])) > math.pi / 2:  # the same line, other normal
            rho, alpha = -rho, float(_wrap(alpha + math.pi))
            cov = cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
            side = int(_swap_sides(side))
        self._sides[k] |= side
        ends = np.vstack((self._ends(k), _ends_of(line[None])[0]))
        self._combine(k, rho, alpha, cov)
        self._t[k] = _extent(self._rho[k], self._alpha[k], ends)
        self._box[k] = boxes_of(self._ends(k)[None], 0.0)[0]
        if self._last[k] != scan_index:
            self._scans[k] += 1
        self._returns[k] += n_points
        self._fused[k] += 1
        self._first[k] = min(self._first[k], scan_index)
        self._last[k] = max(self._last[k], scan_index)
        self.segments_fused += 1

    def _combine(self, k: int, rho: float, alpha: float, cov: np.ndarray) -> None:
        """Information-weighted mean of line ``k`` and ``(rho, alpha, cov)``."""
        info_m = _inverse(self._cov[k])
        info_s = _inverse(cov)
        fused_cov = _inverse(info_m + info_s)
        mean_m = np.array([self._rho[k], self._alpha[k]])
        mean_s = np.array([rho, self._alpha[k] + _wrap(alpha - self._alpha[k])])
        mean = fused_cov @ (info_m @ mean_m + info_s @ mean_s)
        if mean[0] < 0:
            mean = np.array([-mean[0], mean[1] + math.pi])
            fused_cov = fused_cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
            self._sides[k] = _swap_sides(self._sides[k])
        self._rho[k], self._alpha[k] = mean[0], float(_wrap(mean[1]))
        self._cov[k] = (fused_cov + fused_cov.T) / 2

    def _ends(self, k: int) -> np.ndarray:
        return _points_at(self._rho[k], self._alpha[k], self._t[k])

    def _all_ends(self) -> np.ndarray:
        """``L x 2 x 2`` endpoints of every line's extent."""
        n = self._n
        alpha, t = self._alpha[:n], self._t[:n]
        normal = np.stack((np.cos(alpha), np.sin(alpha)), axis=-1)
        tangent = np.stack((-np.sin(alpha), np.cos(alpha)), axis=-1)
        return (self._rho[:n, None] * normal)[:, None, :] + t[:, :, None] * tangent[:, None, :]

    # -- the map as a whole ----------------------------------------------------------------

    def merge_agreeing(self) -> int:
        """Merge every pair of lines that agree (the gates of association); how many went."""
        merged = 0
        for _ in range(4):  # each pass merges disjoint pairs; a few passes settle chains
            n = self._n
            if n < 2:
                break
            ends = self._all_ends()
            margin = np.array([-1.0, -1.0, 1.0, 1.0]) * self.settings.max_gap
            i, j = box_pairs(self._box[:n] + margin, self._box[:n])
            upper = i < j
            i, j = i[upper], j[upper]
            d2 = self._agreement(
                self._rho[i], self._alpha[i], self._cov[i], ends[i],
                self._rho[j], self._alpha[j], self._cov[j], self._t[j],
            )  # fmt: skip
            passed = np.isfinite(d2)
            if not passed.any():
                break
            i, j, d2 = i[passed], j[passed], d2[passed]
            order = np.argsort(d2, kind="stable")
            used = np.zeros(n, dtype=bool)
            gone = []
            for a, b in zip(i[order].tolist(), j[order].tolist(), strict=True):
                if used[a] or used[b]:
                    continue
                used[a] = used[b] = True
                self._absorb(a, b)
                gone.append(b)
            self._remove(np.array(gone, dtype=np.int64))
            merged += len(gone)
        return merged

    def _absorb(self, i: int, j: int) -> None:
        """Line ``j`` fused into line ``i`` (``j`` is removed by the caller)."""
        ends = np.vstack((self._ends(i), self._ends(j)))
        rho, alpha, cov = self._rho[j], self._alpha[j], self._cov[j]
        side = self._sides[j]
        if abs(_wrap(alpha - self._alpha[i])) > math.pi / 2:
            rho, alpha = -rho, float(_wrap(alpha + math.pi))
            cov = cov * np.array([[1.0, -1.0], [-1.0, 1.0]])
            side = _swap_sides(side)
        self._sides[i] |= side
        self._combine(i, rho, alpha, cov)
        self._t[i] = _extent(self._rho[i], self._alpha[i], ends)
        self._box[i] = boxes_of(self._ends(i)[None], 0.0)[0]
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
                     "_fused", "_box", "_sides"):  # fmt: skip
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

    def settled(self, floor: int) -> tuple[np.ndarray, ...]:
        """``rho, alpha, start, end, sides`` of the lines seen by ``floor`` scans or more so
        far."""
        keep = np.flatnonzero(self._scans[: self._n] >= floor)
        ends = self._all_ends()[keep]
        return self._rho[keep], self._alpha[keep], ends[:, 0], ends[:, 1], self._sides[keep]

    def lines(self, min_scans: int | None = None) -> MapLines:
        """The map: lines seen by at least ``min_scans`` scans (default: the settings')."""
        self.merge_agreeing()
        n = self._n
        floor = self.settings.min_scans if min_scans is None else min_scans
        keep = np.flatnonzero(self._scans[:n] >= floor)
        ends = self._all_ends()[keep]
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
            origin=self.frame.origin,
            sides=self._sides[keep].copy(),
        )


def _ends_of(lines: np.ndarray) -> np.ndarray:
    """``S x 2 x 2`` endpoints (start, end) of world-frame segment rows."""
    return np.stack((lines[:, [START_X, START_Y]], lines[:, [END_X, END_Y]]), axis=1).astype(
        np.float64
    )


def _inverse(m: np.ndarray) -> np.ndarray:
    """The inverse of a 2 x 2 covariance (closed form)."""
    a, b, c, d = float(m[0, 0]), float(m[0, 1]), float(m[1, 0]), float(m[1, 1])
    det = a * d - b * c
    return np.array([[d, -b], [-c, a]]) / det


def _extent(rho: float, alpha: float, points: np.ndarray) -> np.ndarray:
    """``[t_min, t_max]`` of ``points`` along the line's tangent."""
    along = points @ np.array([-math.sin(alpha), math.cos(alpha)])
    return np.array([along.min(), along.max()])


def _points_at(rho: float, alpha: float, t: np.ndarray) -> np.ndarray:
    """Points of the line at tangent coordinates ``t`` (``2 x 2``)."""
    normal = np.array([math.cos(alpha), math.sin(alpha)])
    tangent = np.array([-math.sin(alpha), math.cos(alpha)])
    return rho * normal[None, :] + np.asarray(t)[:, None] * tangent[None, :]
