"""Global localisation on a line map: pose hypotheses from a scan's segments, kept when scans agree.

::

    from scanlines.map.relocalise import GlobalSearch

    search = GlobalSearch(tracker)              # a LineMapFilter on the map
    search.explained(points, pose)              # share of returns near a map line
    search.propose(scan, odometry_state)        # hypotheses from the scan's segments
    search.step(points, increment)              # each scan: hypotheses tracked and scored
    search.winner()                             # the hypothesis scans agreed on, or None

Two scan segments that are not parallel, matched to two map lines whose angle between them
is the same, fix a pose: the turn from the angles, the position from the two lines' offsets
(the sensor on a side each map line was seen from, each segment overlapping its map line).
Every such pair of the scan's longest segments against every pair of map lines gives the
candidates. Where no two cross (a corridor's two walls) and no hypothesis explains the scans
yet, one segment on a map line and a segment's real end (a jump: a doorway's jamb; a
corner) on a map line's end point fix a pose (:func:`end_candidates`). Each candidate is
scored by the share of the scan's returns within ``near`` of a map line
(:class:`ExplainedGrid`: a bitmap of the cells near the map's lines), and the best distinct
ones become hypotheses. Each hypothesis is then a copy of the filter (with the
odometry's errors learnt so far), stepped on the next scans like the filter itself and
scored again on each; a hypothesis is kept when it has explained at least ``found_share``
of the returns over ``agree`` scans and no distinct rival comes within ``margin`` of it.
Where the map holds only part of what the sensor sees, a hypothesis leading its rivals may
instead be judged where the map has lines (:func:`~scanlines.map.scoring.mapped`: its beams
cast on the map's lines over ``agree_far`` scans, few seen through a wall, most of those
that meet a map line explained).
"""

from __future__ import annotations

import copy
import math
from collections import deque

import numpy as np

from scanlines.geometry.poses import Pose, compose
from scanlines.map.candidates import LineEnds, LinePairs, end_candidates, pose_candidates
from scanlines.map.scoring import ExplainedGrid, beam_shares, mapped
from scanlines.map.search_settings import SearchSettings

__all__ = ["ExplainedGrid", "GlobalSearch", "Hypothesis", "LineEnds", "LinePairs",
           "SearchSettings", "end_candidates", "pose_candidates"]  # fmt: skip


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _distinct(poses: np.ndarray, scores: np.ndarray, settings: SearchSettings, count: int):
    """The best ``count`` of ``poses`` by ``scores``, each distinct from the better ones."""
    kept: list[int] = []
    for k in np.argsort(-scores, kind="stable"):
        if len(kept) >= count:
            break
        if all(not _same(poses[k], poses[q], settings) for q in kept):
            kept.append(int(k))
    return kept


def _same(p, q, settings: SearchSettings) -> bool:
    return (
        math.hypot(p[0] - q[0], p[1] - q[1]) < settings.distinct_distance
        and abs(float(_wrap(p[2] - q[2]))) < settings.distinct_angle
    )


class Hypothesis:
    """A pose hypothesis: a copy of the filter, the odometry's move since its last step
    (it is stepped every ``refine_every`` scans, dead-reckoned between), and the shares
    of returns it explained, scan by scan."""

    def __init__(self, tracker) -> None:
        self.tracker = tracker
        self.pending: Pose = (0.0, 0.0, 0.0)
        self.shares: list[float] = []
        self.crossed: list[float] = []  # shares of beams through a map line, when checked
        self.poses: list[Pose] = []  # its pose at each share
        self.beams: dict[int, tuple[float, float]] = {}  # beam_shares by the search's scan
        self.pose: Pose = self._pose()

    def _pose(self) -> Pose:
        return compose(tuple(float(v) for v in self.tracker.state[:3]), self.pending)

    def move(self, increment: Pose | None, points: np.ndarray | None) -> None:
        """Moved by the odometry ``increment``; stepped through the filter on ``points``
        (sensor-frame returns) when given."""
        if increment is not None:
            self.pending = compose(self.pending, increment)
        if points is not None:
            self.tracker.step(points, None if self.pending == (0.0, 0.0, 0.0) else self.pending)
            self.pending = (0.0, 0.0, 0.0)
        self.pose = self._pose()

    def recent(self, count: int) -> float:
        last = self.shares[-count:]
        return sum(last) / len(last) if last else 0.0


class GlobalSearch:
    """Hypotheses on the map of ``tracker`` (a :class:`~scanlines.map.filter.
    LineMapFilter`, whose lines and settings the hypotheses share)."""

    def __init__(self, tracker, settings: SearchSettings | None = None, extractor=None) -> None:
        self.settings = settings or SearchSettings()
        self.tracker = tracker
        self._extractor = extractor
        lines = tracker.lines
        self.grid = ExplainedGrid(lines.start, lines.end, self.settings.near, self.settings.cell)
        self._pairs: LinePairs | None = None
        self._ends: LineEnds | None = None
        self.hypotheses: list[Hypothesis] = []
        self._scans = 0
        self._picks: dict[int, np.ndarray] = {}  # the returns scored, by the scan's size
        self._samples: deque[np.ndarray] = deque(maxlen=self.settings.agree_far)

    @property
    def pairs(self) -> LinePairs:
        """The map's line pairs, made the first time a pose is searched for."""
        if self._pairs is None:
            self._pairs = LinePairs(self.tracker.lines, self.settings)
        return self._pairs

    @property
    def ends(self) -> LineEnds:
        """The map's line end points, made the first time a pose is searched for."""
        if self._ends is None:
            self._ends = LineEnds(self.tracker.lines, self.settings)
        return self._ends

    def sample(self, points: np.ndarray) -> np.ndarray:
        """The returns scored (evenly subsampled)."""
        count = self.settings.score_points
        if len(points) <= count:
            return points
        picks = self._picks.get(len(points))
        if picks is None:
            picks = np.linspace(0, len(points) - 1, count).round().astype(np.intp)
            self._picks[len(points)] = picks
        return points[picks]

    def explained(self, points: np.ndarray, pose: Pose) -> float:
        """The share of the scan's returns within ``near`` of a map line at ``pose``."""
        return self.grid.share_at(self.sample(points), pose)

    def propose(self, scan, points: np.ndarray, errors=None) -> int:
        """New hypotheses from ``scan``'s segments (``points``: its valid returns, sensor
        frame; ``errors``: the odometry's errors and their covariance to start them with,
        ``state[3:]`` of the filter and its block); how many. Where no two segments cross
        (a corridor's walls) and no hypothesis explains the scans yet, candidates from a
        segment's end on a map line's end (:func:`end_candidates`) too."""
        from scanlines.extractor import Extractor

        s = self.settings
        if self._extractor is None:
            self._extractor = Extractor()
        extraction = self._extractor(scan)
        rows = np.asarray(extraction.lines)[:, :6]
        sample = self.sample(points)
        poses = pose_candidates(rows, self.tracker.lines, self.pairs, s)
        added = self._add(poses, s.candidates, sample, points, errors)
        if s.end_candidates and not len(poses) and not self._held():
            kinds = np.asarray(extraction.end_kinds)
            poses = end_candidates(rows, kinds, self.tracker.lines, self.ends, s)
            added += self._add(poses, s.end_candidates, sample, points, errors)
        self._trim()
        return added

    def _held(self) -> bool:
        """Whether a hypothesis explains ``found_share`` over its last ``agree`` scans."""
        s = self.settings
        return any(h.recent(s.agree) >= s.found_share for h in self.hypotheses)

    def _add(self, poses, count: int, sample, points, errors) -> int:
        """The best ``count`` distinct of ``poses`` made hypotheses (those explaining at
        least ``drop_share`` of ``sample``, none the same as a hypothesis); how many."""
        s = self.settings
        if not len(poses):
            return 0
        scores = self.grid.shares(sample, poses)
        added = 0
        for k in _distinct(poses, scores, s, count):
            if scores[k] < s.drop_share:
                break
            if any(_same(poses[k], h.pose, s) for h in self.hypotheses):
                continue
            hypothesis = self._hypothesis(poses[k], errors)
            hypothesis.move(None, points)  # aligned on the scan it came from
            hypothesis.shares.append(float(self.grid.shares(sample, hypothesis.pose)[0]))
            hypothesis.poses.append(hypothesis.pose)
            self.hypotheses.append(hypothesis)
            added += 1
        return added

    def _hypothesis(self, pose, errors) -> Hypothesis:
        s = self.settings
        tracker = copy.copy(self.tracker)
        tracker.start(tuple(float(v) for v in pose), (s.sigma_xy, s.sigma_theta))
        if errors is not None:
            tracker.state[3:] = errors[0]
            tracker.covariance[3:, 3:] = errors[1]
        return Hypothesis(tracker)

    def step(self, points: np.ndarray, increment: Pose | None, tracked: bool = False) -> None:
        """Each hypothesis moved by the odometry (stepped through its filter every
        ``refine_every`` scans, ``refine_every_tracked`` while the filter still has a pose
        of its own: a long search there is mostly a place the map lacks) and scored on the
        scan (sensor-frame returns); the poor and the duplicates dropped."""
        s = self.settings
        self._scans += 1
        self._samples.append(self.sample(points))
        refine = self._scans % (s.refine_every_tracked if tracked else s.refine_every) == 0
        for h in self.hypotheses:
            h.move(increment, points if refine else None)
        if self.hypotheses:
            poses = np.array([h.pose for h in self.hypotheses])
            shares = self.grid.shares(self.sample(points), poses)
            for h, share in zip(self.hypotheses, shares, strict=True):
                h.shares.append(float(share))
                h.poses.append(h.pose)
        kept: list[Hypothesis] = []
        for h in sorted(self.hypotheses, key=lambda h: -len(h.shares)):
            if len(h.shares) >= s.drop_after and h.recent(s.drop_after) < s.drop_share:
                continue
            if refine and any(_same(h.pose, k.pose, s) for k in kept):
                continue  # two that became one (checked when they are refined)
            kept.append(h)
        self.hypotheses = kept

    def _mapped(self, h: Hypothesis) -> bool:
        """:func:`~scanlines.map.scoring.mapped` over the last ``agree_far`` scans, the beams
        cast only for a hypothesis explaining ``mapped_share`` (the costly part)."""
        s = self.settings
        count = s.agree_far
        if len(h.shares) < count or len(self._samples) < count:
            return False
        if h.recent(count) < s.mapped_share:
            return False
        beams = []
        for back in range(1, count + 1):
            scan = self._scans - back + 1
            if scan not in h.beams:
                sample, pose = self._samples[-back], h.poses[-back]
                explained = self.grid.hits_at(sample, pose)
                h.beams[scan] = beam_shares(
                    sample, pose, explained, self.tracker.lines, s.clearance, s.reach
                )
            beams.append(h.beams[scan])
        for old in [k for k in h.beams if k <= self._scans - count]:
            del h.beams[old]
        return mapped(h.shares, beams[::-1], count, s)

    def _trim(self) -> None:
        s = self.settings
        if len(self.hypotheses) > s.max_hypotheses:
            self.hypotheses.sort(key=lambda h: -h.recent(s.agree))
            del self.hypotheses[s.max_hypotheses :]

    def winner(self, points: np.ndarray, rival: float = 0.0, near=None) -> Hypothesis | None:
        """The hypothesis the last scans agree on: one ``near`` the filter's own pose
        (``near()`` gives the test of a pose; none: no pose yet) after ``agree`` scans explaining
        ``found_share`` of the returns, one farther after ``agree_far`` scans explaining
        ``found_share_far``; neither another distinct hypothesis nor ``rival`` (the
        filter's own share over the same scans) came within ``margin`` of it; and at most
        ``max_crossed`` of the scan's returns (``points``) were seen through a map line
        from it (else it is dropped)."""
        s = self.settings
        best, best_score = None, -1.0
        if near is not None and any(len(h.shares) >= s.agree for h in self.hypotheses):
            near = near()  # the filter's uncertainty, worked out when a hypothesis is ready
        for h in self.hypotheses:
            if len(h.shares) < s.agree:
                continue
            close = near is not None and near(h.pose)
            count, floor = (s.agree, s.found_share) if close else (s.agree_far, s.found_share_far)
            if len(h.shares) < count:
                continue
            score = h.recent(count)
            if score < rival + s.margin or score <= best_score:
                continue
            if score >= floor or (self._leads(h) and self._mapped(h)):
                best, best_score = h, score
        if best is None or not self._leads(best):
            return None
        if self._mapped(best):
            return best  # its beams cast on the map's lines: none seen through a wall
        best.crossed.append(self.grid.crossed(self.sample(points), best.pose, s.clearance, s.reach))
        if len(best.crossed) < s.checks or np.mean(best.crossed[-s.checks :]) > s.max_crossed:
            return None
        return best

    def _leads(self, best: Hypothesis) -> bool:
        """Whether no hypothesis distinct from ``best`` comes within ``margin`` of it over
        the last ``agree`` scans."""
        s = self.settings
        lead = best.recent(s.agree) - s.margin
        return not any(
            h is not best and h.recent(s.agree) > lead and not _same(h.pose, best.pose, s)
            for h in self.hypotheses
        )

    def settle(self, winner: Hypothesis) -> None:
        """The winner's pending move applied through its filter (no returns matched)."""
        if winner.pending != (0.0, 0.0, 0.0):
            winner.move(None, np.zeros((0, 2)))

    def clear(self) -> None:
        self.hypotheses = []
        self._scans = 0
        self._samples.clear()
