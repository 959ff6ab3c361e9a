"""Localisation on a saved line map: a log tracked from a given pose, odometry as the prior.

::

    from scanlines.io import open_log
    from scanlines.map.localize import localize, read_line_map

    lines, frame = read_line_map("intel.json")           # a map `scanlines map` wrote
    with open_log("intel.clf.gz") as reader:
        run = localize(reader.enumerate(), lines, frame, (t0, (x0, y0, yaw0)))
    run.tracked                                            # poses, covariances, status

The run starts at the scan of time ``t0``: the first (in the log's order) within
:data:`START_TOLERANCE` of it, else the first after it; the scans before it are skipped.
From there every scan is tracked in the log's order, whatever its clock says: a raw log's
clock may step back (the raw Intel scans' by up to 0.9 s, 265 times) while its odometry
runs on, and the log's order is the order of the odometry. So the start is chosen among
the scans up to :data:`START_WINDOW` past ``t0``: on the raw Intel scans the scan stamped
33.108 s comes before the one stamped 32.907 s, and the robot turned 6.7 degrees between
them. Each scan goes through :class:`~scanlines.map.filter.LineMapFilter`:
the pose predicted from the last one by the odometry increment (corrected by the odometry's
heading drift, scale and the sensor's lever, which the filter learns), then its returns
matched to the map's lines. A scan that does not fit is reported (``status`` ``"did not
fit"``), not forced: its predicted pose stands with the covariance grown by the increment's
noise, which widens the gate of the next scans until one fits again.

Earlier versions (docs/MEASUREMENTS.md) took only the increment's noise as each fit's prior
and searched every map line for every return: 0.21 m RMSE over the raw Intel keyframes at
252 scans/s; the filter, its matching (local lines, a grid of the map's lines) and the
odometry's learnt errors give the figures measured there now.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from scanlines.errors import NO_SUCH_FILE, ScanlinesError, describe
from scanlines.geometry.poses import Pose, relative_pose
from scanlines.map.align import LineSet
from scanlines.map.build import TrackedPose
from scanlines.map.export import SIDE_NAMES
from scanlines.map.filter import INITIAL_SIGMA, FilterSettings, LineMapFilter
from scanlines.map.frame import MAX_COORDINATE, MAX_EXTENT, LocalFrame
from scanlines.map.fusion import BOTH
from scanlines.map.relocalise import GlobalSearch, SearchSettings
from scanlines.scan import Scan
from scanlines.untrusted import UntrustedInput, load_json, quote, read_regular_file

__all__ = ["Localisation", "MapFileError", "localize", "read_line_map"]

#: A scan this close (seconds) to the initial time is the scan of the initial pose.
START_TOLERANCE = 0.01
#: The scans read past the initial time (seconds of the log's clock) to find its scan.
START_WINDOW = 1.0


class MapFileError(ScanlinesError, ValueError):
    """A line map file that cannot be read."""


#: Largest map file read (a map line is about 500 bytes).
MAX_MAP_BYTES = 1 << 30
#: How far (metres) a line's ends may lie from its ``(rho, alpha)``: the writer puts them
#: on it (to 1e-14 m on the Intel excerpt's map); more means one of them was changed.
END_TOLERANCE = 1e-3
#: The map lines a file may hold.
MAX_MAP_LINES = 10_000_000


def read_line_map(path: str | Path) -> tuple[LineSet, LocalFrame]:
    """The lines of a ``.json`` map ``scanlines map`` wrote, in its local frame.

    The file is data to distrust: a regular file of at most :data:`MAX_MAP_BYTES`, nested
    a few levels deep; every coordinate a finite number (not a boolean) within the limits
    a map takes (:mod:`scanlines.map.frame`: ``|x|, |y| <= 1e9`` m, ends within 1e5 m of
    the origin); ``rho`` and ``alpha`` consistent with the ends (within
    :data:`END_TOLERANCE`); a covariance, where given, 2 x 2, symmetric and positive
    semi-definite; ``seen_from``, where given, one of the names of
    :data:`~scanlines.map.export.SIDE_NAMES` (absent: both sides). Anything else is a
    :class:`MapFileError` of one line naming the file, the line and the field.
    """
    path = Path(path)
    document = _map_document(path)
    if not isinstance(document, dict) or document.get("format") != "scanlines line map":
        raise MapFileError(f"{path}: not a line map (`scanlines map --out MAP.json` writes one)")
    frame = _map_frame(path, document.get("frame"))
    records = document.get("lines")
    if not isinstance(records, list):
        raise MapFileError(f"{path}: field lines: not a list")
    if len(records) > MAX_MAP_LINES:
        raise MapFileError(f"{path}: field lines: more than {MAX_MAP_LINES} lines")
    values = np.zeros((len(records), 6))
    sides = np.full(len(records), BOTH, dtype=np.int8)
    for k, record in enumerate(records):
        values[k] = _map_line(f"{path}: line {k}", record, frame)
        sides[k] = _seen_from(record, f"{path}: line {k}")
    offset = np.array(frame.origin)
    lines = LineSet(
        values[:, 4], values[:, 5], values[:, 0:2] - offset, values[:, 2:4] - offset, sides
    )
    return lines, frame


def _map_document(path: Path) -> Any:
    """The JSON document of the map file ``path``, read at a bounded cost."""
    try:
        return load_json(read_regular_file(path, MAX_MAP_BYTES))
    except FileNotFoundError:
        raise MapFileError(f"{path}: {NO_SUCH_FILE}") from None
    except OSError as error:
        raise MapFileError(f"{path}: cannot read the map: {error.strerror}") from None
    except UntrustedInput as error:
        raise MapFileError(f"{path}: not a line map: {error}") from None
    except UnicodeDecodeError as error:
        raise MapFileError(f"{path}: not a text file ({error.reason})") from None
    except json.JSONDecodeError as error:
        raise MapFileError(f"{path}: not JSON ({error.msg}, line {error.lineno})") from None
    except ValueError as error:  # an integer too long for Python to convert
        raise MapFileError(f"{path}: not a line map: {describe(error)}") from None


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _point(value: Any, where: str) -> tuple[float, float]:
    """A pair of finite numbers within :data:`MAX_COORDINATE` (booleans are no numbers)."""
    if not (isinstance(value, list) and len(value) == 2 and all(map(_is_number, value))):
        raise MapFileError(f"{where}: missing or not a pair of numbers, got {quote(value)}")
    try:
        x, y = float(value[0]), float(value[1])
    except OverflowError:
        raise MapFileError(f"{where}: not finite") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise MapFileError(f"{where}: not finite")
    if max(abs(x), abs(y)) > MAX_COORDINATE:
        raise MapFileError(f"{where}: {quote(value)} is beyond the map's limit |x|, |y| <= 1e9 m")
    return x, y


def _map_frame(path: Path, frame: Any) -> LocalFrame:
    if not isinstance(frame, dict) or "origin" not in frame:
        raise MapFileError(f"{path}: field frame.origin: not a pair of numbers")
    return LocalFrame(*_point(frame["origin"], f"{path}: field frame.origin"))


def _map_line(where: str, record: Any, frame: LocalFrame) -> list[float]:
    """``[x0, y0, x1, y1, rho, alpha]`` of one line record, checked (:func:`read_line_map`)."""
    if not isinstance(record, dict):
        raise MapFileError(f"{where}: not a record of start, end, rho, alpha")
    ends = []
    for name in ("start", "end"):
        x, y = _point(record.get(name), f"{where}: field {name}")
        far = max(abs(x - frame.x0), abs(y - frame.y0))
        if far > MAX_EXTENT:
            raise MapFileError(
                f"{where}: field {name}: {far:.6g} m from the map's origin, beyond the map's "
                "limit of 1e5 m"
            )
        ends.append((x - frame.x0, y - frame.y0))
    rho, alpha = (_scalar(record.get(name), f"{where}: field {name}") for name in ("rho", "alpha"))
    normal = (math.cos(alpha), math.sin(alpha))
    off = max(abs(normal[0] * x + normal[1] * y - rho) for x, y in ends)
    if not off <= END_TOLERANCE:
        raise MapFileError(
            f"{where}: fields rho, alpha: the line does not pass through its ends (one is "
            f"{off:.3g} m off it; at most {END_TOLERANCE:g} m)"
        )
    if "covariance" in record:
        _check_covariance(record["covariance"], f"{where}: field covariance")
    (x0, y0), (x1, y1) = ends
    return [x0 + frame.x0, y0 + frame.y0, x1 + frame.x0, y1 + frame.y0, rho, alpha]


def _scalar(value: Any, where: str) -> float:
    if not _is_number(value):
        raise MapFileError(f"{where}: missing or not a number")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise MapFileError(f"{where}: not finite")
    return number


def _check_covariance(value: Any, where: str) -> None:
    """A 2 x 2 matrix (of rho, alpha) of finite numbers, symmetric, positive
    semi-definite (to rounding)."""
    shaped = isinstance(value, list) and len(value) == 2
    if not (shaped and all(isinstance(row, list) and len(row) == 2 for row in value)):
        raise MapFileError(f"{where}: not a 2 x 2 matrix, got {quote(value)}")
    if not all(_is_number(v) for row in value for v in row):
        raise MapFileError(f"{where}: not a 2 x 2 matrix of numbers, got {quote(value)}")
    try:
        matrix = np.array(value, dtype=np.float64)
    except OverflowError:  # an integer beyond a double
        raise MapFileError(f"{where}: not finite") from None
    if not np.isfinite(matrix).all():
        raise MapFileError(f"{where}: not finite")
    scale = float(np.abs(matrix).max())
    if abs(matrix[0, 1] - matrix[1, 0]) > 1e-9 * scale:
        raise MapFileError(f"{where}: not symmetric, got {quote(value)}")
    if float(np.linalg.eigvalsh(matrix).min()) < -1e-12 * scale:
        raise MapFileError(f"{where}: not positive semi-definite, got {quote(value)}")


def _seen_from(record: dict, where: str) -> int:
    """The sides a map line was seen from (field ``seen_from``; a map written before sides
    were kept has none: both)."""
    name = record.get("seen_from", SIDE_NAMES[BOTH])
    for side, known in SIDE_NAMES.items():
        if isinstance(name, str) and name == known:
            return side
    raise MapFileError(
        f"{where}: field seen_from: {quote(name)} is not one of "
        + ", ".join(repr(v) for v in SIDE_NAMES.values())
    )


@dataclass
class Localisation:
    """A localisation run: every tracked scan (local frame; ``frame.world_pose`` for the
    world), the scans skipped before the initial time or without a pose."""

    frame: LocalFrame
    tracked: list[TrackedPose] = field(default_factory=list)
    skipped: int = 0
    without_pose: int = 0
    #: The odometry's errors as learnt at the end (:class:`~scanlines.map.filter.
    #: LineMapFilter`): heading drift (radians per metre), scale error, the sensor's lever.
    drift: float = 0.0
    scale: float = 0.0
    lever: tuple[float, float] = (0.0, 0.0)
    #: The scans at which the filter declared itself lost, and was found again.
    lost_at: list[int] = field(default_factory=list)
    found_at: list[int] = field(default_factory=list)

    @property
    def not_fit(self) -> int:
        return sum(1 for t in self.tracked if t.status == "did not fit")


def _reporting(indexed: Iterable[tuple[int, Scan]], on_scan: Callable[[int], None] | None):
    """``indexed``, calling ``on_scan(index)`` as each pair is read."""
    for index, scan in indexed:
        if on_scan is not None:
            on_scan(index)
        yield index, scan


def _from_start(indexed: Iterable[tuple[int, Scan]], t0: float, run: Localisation):
    """``indexed`` from the scan of time ``t0`` on (module docstring), counting the scans
    skipped before it in ``run``."""
    scans = iter(indexed)
    pending: list[tuple[int, Scan]] = []
    for index, scan in scans:
        t = scan.timestamp
        if not pending and (t is None or t < t0 - START_TOLERANCE):
            run.skipped += 1
            continue
        pending.append((index, scan))
        if t is not None and t > t0 + START_WINDOW:
            break
    times = [scan.timestamp for _, scan in pending]
    near = [k for k, t in enumerate(times) if t is not None and abs(t - t0) <= START_TOLERANCE]
    after = [k for k, t in enumerate(times) if t is not None and t >= t0]
    first = near[0] if near else after[0] if after else len(pending)
    run.skipped += first
    yield from pending[first:]
    yield from scans


def localize(
    indexed: Iterable[tuple[int, Scan]],
    lines: LineSet,
    frame: LocalFrame,
    initial: tuple[float, Pose] | None,
    *,
    poses: Callable[[int, Scan], Pose | None] | None = None,
    settings: FilterSettings | None = None,
    initial_sigma: tuple[float, float] = INITIAL_SIGMA,
    search: SearchSettings | None = None,
    on_scan: Callable[[int], None] | None = None,
) -> Localisation:
    """Track ``indexed`` scans on ``lines`` (local ``frame``) from ``initial``: a time
    and a world pose (standard deviations ``initial_sigma``: metres, radians), or ``None``:
    lost from the first scan, found by global localisation (:mod:`scanlines.map.relocalise`,
    ``search`` its settings), as when the filter judges itself lost on the way. ``poses``:
    each scan's odometry (default: the pose it carries); ``on_scan(index)``: called for
    each scan read, skipped ones too."""
    run = Localisation(frame)
    tracker = LineMapFilter(lines, settings)
    state = _SearchState(GlobalSearch(tracker, search), lost=initial is None)
    odometry_of = poses or (lambda index, scan: scan.pose)
    last_odometry: Pose | None = None
    returns_of = _Returns()
    indexed = _reporting(indexed, on_scan)
    scans = indexed if initial is None else _from_start(indexed, initial[0], run)
    for index, scan in scans:
        odometry = odometry_of(index, scan)
        if odometry is None:
            run.without_pose += 1
            continue
        if last_odometry is None and initial is not None:
            tracker.start(frame.pose(initial[1]), initial_sigma)
        increment = None if last_odometry is None else relative_pose(last_odometry, odometry)
        points = returns_of(scan)
        predicted, pose, covariance, status = state.step(scan, points, increment)
        last_odometry = odometry
        if status == "lost" and len(run.lost_at) == len(run.found_at):  # once an episode
            run.lost_at.append(index)
        elif status == "found":
            run.found_at.append(index)
        run.tracked.append(
            TrackedPose(index, scan.timestamp, frame.pose(odometry), predicted, pose,
                        covariance, state.status_of(status))
        )  # fmt: skip
    if tracker.state is not None:
        run.drift, run.scale = float(tracker.state[3]), float(tracker.state[4])
        run.lever = (float(tracker.state[5]), float(tracker.state[6]))
    return run


class _Returns:
    """A scan's valid returns in the sensor frame: the rows of :attr:`Scan.points` of its valid
    beams (the same numbers), the cosines and sines of its bearings kept for the next scans
    with the same bearings, as a log's are."""

    def __init__(self) -> None:
        self._bearings: tuple[int, float, float] | None = None
        self._cos = self._sin = np.zeros(0)

    def __call__(self, scan: Scan) -> np.ndarray:
        bearings = (len(scan), scan.angle_min, scan.angle_increment)
        if bearings != self._bearings:
            self._bearings = bearings
            self._cos, self._sin = np.cos(scan.angles), np.sin(scan.angles)
        valid = scan.valid
        r = scan.ranges[valid]
        return np.column_stack((r * self._cos[valid], r * self._sin[valid]))


class _Recovered(NamedTuple):
    """The filter found again by itself (a winner of its own)."""

    pose: Pose
    tracker: LineMapFilter


#: The covariance reported for a scan localised nowhere yet (no initial pose, none found).
UNKNOWN = np.diag([1e6, 1e6, math.pi**2])


class _SearchState:
    """The filter with its global search: whether it is lost, the scans of low share."""

    def __init__(self, search: GlobalSearch, lost: bool) -> None:
        self.search = search
        self.tracker = search.tracker
        self.lost = lost
        self.low = 0
        self.shares: list[float] = []
        self.since_proposal = search.settings.propose_every - 1  # the first scan proposes
        self.lost_for = 0

    def status_of(self, status: str) -> str:
        """The record's status: ``lost`` on every scan while lost."""
        return "lost" if self.lost and status != "found" else status

    def step(self, scan: Scan, points: np.ndarray, increment: Pose | None):
        """The scan through the filter and, while lost, the search: predicted pose, pose,
        covariance, status (``aligned``, ``did not fit``, ``lost`` the first scan lost,
        ``found``)."""
        settings = self.search.settings
        tracker = self.tracker
        started = tracker.state is not None
        was_lost = self.lost
        if started:
            step = tracker.step(points, increment)
            share = self.search.explained(points, step.pose)
            predicted, pose, covariance = step.predicted, step.pose, step.covariance
            status = "aligned" if step.aligned else "did not fit"
        else:
            share, status = 0.0, "lost"
            predicted = pose = (0.0, 0.0, 0.0)
            covariance = UNKNOWN
        self.shares = [*self.shares[-(settings.agree - 1) :], share]
        self.low = self.low + 1 if share < settings.lost_share else 0
        if not self.lost and self.low >= settings.lost_after:
            self.lost, self.since_proposal, self.lost_for = True, settings.propose_every, 0
            return predicted, pose, covariance, "lost"
        if not self.lost:
            return predicted, pose, covariance, status
        found = self._search(scan, points, increment, started)
        if found is not None:
            return predicted, found.pose, found.tracker.covariance[:3, :3].copy(), "found"
        if not started and self.search.hypotheses:
            best = max(self.search.hypotheses, key=lambda h: h.recent(settings.agree))
            pose = best.pose
        return predicted, pose, covariance, "lost" if not was_lost else status

    def _near(self) -> Callable[[Pose], bool]:
        """Whether a pose is within the filter's own uncertainty of its pose."""
        s = self.search.settings
        state, covariance = self.tracker.state, self.tracker.covariance
        assert state is not None
        assert covariance is not None
        sigma = math.sqrt(max(np.linalg.eigvalsh(covariance[:2, :2]).max(), 0.0))
        reach = max(s.near_distance, s.near_sigmas * sigma)
        turn = max(s.near_angle, s.near_sigmas * math.sqrt(covariance[2, 2]))
        x, y, theta = (float(v) for v in state[:3])

        def near(pose: Pose) -> bool:
            return (
                math.hypot(pose[0] - x, pose[1] - y) <= reach
                and abs(math.remainder(pose[2] - theta, 2 * math.pi)) <= turn
            )

        return near

    def _search(self, scan: Scan, points: np.ndarray, increment, started: bool):
        """One scan of the search while lost: the hypotheses stepped, new ones proposed every
        few scans; the winner (if any) becomes the filter's state."""
        search, settings = self.search, self.search.settings
        search.step(points, increment, tracked=started)
        own = float(np.mean(self.shares)) if started else 0.0
        if started and len(self.shares) >= settings.agree and own >= settings.found_share:
            self.lost, self.low = False, 0  # the filter caught the map again by itself
            search.clear()
            return _Recovered(tuple(float(v) for v in self.tracker.state[:3]), self.tracker)
        self.since_proposal += 1
        self.lost_for += 1
        # every few scans at first, then seldom: a long search is an unmapped place
        every = settings.propose_every_tracked if started else settings.propose_every
        if started and self.lost_for > settings.patient:
            every = settings.propose_later
        if self.since_proposal >= every:
            self.since_proposal = 0
            errors = None
            if started:
                errors = (self.tracker.state[3:].copy(), self.tracker.covariance[3:, 3:].copy())
            search.propose(scan, points, errors)
        winner = search.winner(points, own, self._near if started else None)
        if winner is None:
            return None
        search.settle(winner)
        self.tracker.state = winner.tracker.state.copy()
        self.tracker.covariance = winner.tracker.covariance.copy()
        self.tracker._first = False
        self.lost, self.low = False, 0
        self.shares = list(winner.shares[-settings.agree :])
        search.clear()
        return winner
