"""A trajectory scored against a reference: absolute and relative pose error, as evo does.

::

    from scanlines.evaluation.trajectory import load_trajectory, trajectory_error

    error = trajectory_error(load_trajectory("poses.tum"), load_trajectory("corrected.log.gz"))
    error.ate_rmse, error.rpe_rmse          # metres; metres per metre travelled

The figures follow evo (``evo_ape tum REF EST -a`` and ``evo_rpe tum REF EST --delta 1
--delta_unit m --pairs_from_reference``), in the plane:

* **Matching.** Each pose of the shorter trajectory is matched to the pose of the longer
  one nearest in time, if within ``max_diff`` (10 ms); unmatched poses are left out.
* **ATE.** The estimate is aligned to the reference by the least-squares rigid motion of
  the matched positions (Umeyama's method in 2-D: a rotation and a translation, no scale);
  the ATE is the root mean square (and mean, median, max) of the position differences.
* **RPE.** Pairs of matched poses one metre (``delta``) of the reference's path apart,
  consecutive (evo's default, ``all_pairs`` off); for each, the estimate's relative pose
  is compared with the reference's, ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)``; the figure is the
  root mean square of ``E``'s translation (metres per ``delta`` metres travelled) and of
  its angle.

A clock that steps back (the raw Intel log's steps back by up to 0.9 s): each trajectory is
sorted by time (stable) before matching, so the figures are those of the time order; the
steps back are counted (``steps_back``) and reported. evo keeps the file order instead, so
on such a file its RPE may differ slightly (its ATE does not). Two lines at one timestamp
must give the same pose (kept once); two different poses at one time are refused, naming
both (``scanlines.map.poses.read_tum``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ScanlinesError

__all__ = [
    "Trajectory",
    "TrajectoryError",
    "TrajectoryScore",
    "align_se2",
    "load_trajectory",
    "match_times",
    "trajectory_error",
]

#: Two poses further apart in time than this (seconds) are not matched.
MAX_DIFF = 0.01
#: The path length (metres) between the poses of a relative pose error.
DELTA = 1.0
#: File suffixes read as TUM trajectories; anything else is opened as a log.
TUM_SUFFIXES = (".tum", ".txt")


class TrajectoryError(ScanlinesError, ValueError):
    """Trajectories that cannot be scored (no pose, too few matched in time)."""


@dataclass(frozen=True)
class Trajectory:
    """Planar poses ``(x, y, theta)`` (``N x 3``) at ``times`` (sorted), from ``source``;
    ``steps_back``: how often the source's clock stepped back."""

    times: np.ndarray
    poses: np.ndarray
    source: str
    steps_back: int = 0


@dataclass(frozen=True)
class TrajectoryScore:
    """ATE (metres, after alignment) and RPE (per ``delta`` metres of the reference's
    path) of an estimate against a reference; ``None`` where no pair was found."""

    estimate: str
    reference: str
    estimate_poses: int
    reference_poses: int
    matched: int
    max_diff: float
    estimate_steps_back: int
    reference_steps_back: int
    alignment: tuple[float, float, float]
    ate_rmse: float
    ate_mean: float
    ate_median: float
    ate_max: float
    ate_rotation_rmse_deg: float
    path_length: float
    delta: float
    rpe_pairs: int
    rpe_rmse: float | None
    rpe_mean: float | None
    rpe_max: float | None
    rpe_rotation_rmse_deg: float | None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _steps_back(times: np.ndarray) -> int:
    return int(np.count_nonzero(np.diff(times) < 0))


def _sorted(times, poses, source: str, steps_back: int) -> Trajectory:
    order = np.argsort(times, kind="stable")
    return Trajectory(times[order], poses[order], source, steps_back)


def _tum_times(path: Path) -> np.ndarray:
    """The timestamps of a TUM file in file order (the file already read by ``read_tum``)."""
    times = []
    for line in path.read_text(encoding="utf-8").splitlines():
        fields = line.split()
        if fields and not fields[0].startswith("#"):
            times.append(float(fields[0]))
    return np.array(times)


def load_trajectory(path: str | Path) -> Trajectory:
    """A trajectory from a TUM file (``.tum``, ``.txt``) or from the poses of a log (any
    format ``scanlines info`` reads; each scan's time and pose, scans without either
    left out)."""
    from scanlines.map.poses import PoseError, _unique_times, read_tum

    path = Path(path)
    if path.suffix.lower() in TUM_SUFFIXES:
        read = read_tum(path)
        return Trajectory(read.times, read.poses, path.name, _steps_back(_tum_times(path)))
    from scanlines.io import open_log

    times, poses, numbers = [], [], []
    with open_log(path) as reader:
        for index, scan in reader.enumerate():
            if scan.timestamp is None or scan.pose is None:
                continue
            times.append(float(scan.timestamp))
            poses.append(tuple(float(v) for v in scan.pose))
            numbers.append(index)
    if not times:
        raise PoseError(f"{path}: no scan carries both a timestamp and a pose")
    t, p = np.array(times), np.array(poses)
    if not (np.isfinite(t).all() and np.isfinite(p).all()):
        bad = int(numbers[int(np.flatnonzero(~(np.isfinite(t) & np.isfinite(p).all(1)))[0])])
        raise PoseError(f"{path}: scan {bad}: the timestamp or pose is not finite")
    try:
        keep = _unique_times(t, p, np.array(numbers), path)
    except PoseError as error:
        raise PoseError(str(error).replace(": lines ", ": scans ")) from None
    return _sorted(t[keep], p[keep], path.name, _steps_back(t))


def match_times(a: np.ndarray, b: np.ndarray, max_diff: float = MAX_DIFF):
    """Index arrays ``(i, j)``: each time of the shorter of the sorted ``a``, ``b`` matched
    to the nearest of the longer within ``max_diff`` (evo's ``associate_trajectories``)."""
    swap = len(b) < len(a)
    short, long = (b, a) if swap else (a, b)
    if not len(short) or not len(long):
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    right = np.clip(np.searchsorted(long, short, side="right"), 0, len(long) - 1)
    left = np.clip(right - 1, 0, len(long) - 1)
    use_left = np.abs(short - long[left]) <= np.abs(long[right] - short)
    nearest = np.where(use_left, left, right)
    ok = np.abs(long[nearest] - short) <= max_diff
    i, j = np.flatnonzero(ok), nearest[ok]
    return (j, i) if swap else (i, j)


def align_se2(source: np.ndarray, target: np.ndarray) -> tuple[float, float, float]:
    """The rigid motion ``(x, y, theta)`` taking ``source`` points (``N x 2``) closest to
    ``target`` in least squares (Umeyama, no scale)."""
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    cov = (target - mu_t).T @ (source - mu_s) / len(source)
    u, _, vt = np.linalg.svd(cov)
    d = np.diag([1.0, float(np.sign(np.linalg.det(u) * np.linalg.det(vt)) or 1.0)])
    rotation = u @ d @ vt
    t = mu_t - rotation @ mu_s
    return (float(t[0]), float(t[1]), math.atan2(rotation[1, 0], rotation[0, 0]))


def _moved(poses: np.ndarray, motion: tuple[float, float, float]) -> np.ndarray:
    x, y, theta = motion
    c, s = math.cos(theta), math.sin(theta)
    out = np.empty_like(poses)
    out[:, 0] = x + c * poses[:, 0] - s * poses[:, 1]
    out[:, 1] = y + s * poses[:, 0] + c * poses[:, 1]
    out[:, 2] = np.remainder(poses[:, 2] + theta + np.pi, 2 * np.pi) - np.pi
    return out


def _relative(poses: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Pose ``j`` in the frame of pose ``i``, for each pair."""
    d = poses[j, :2] - poses[i, :2]
    c, s = np.cos(poses[i, 2]), np.sin(poses[i, 2])
    turn = np.remainder(poses[j, 2] - poses[i, 2] + np.pi, 2 * np.pi) - np.pi
    return np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], turn))


def _path_pairs(positions: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive pairs ``delta`` metres of path apart (evo's ``filter_pairs_by_path``)."""
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    ids, path = [0], 0.0
    for k, step in enumerate(steps, start=1):
        path += float(step)
        if path >= delta:
            ids.append(k)
            path = 0.0
    return np.array(ids[:-1], np.intp), np.array(ids[1:], np.intp)


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2)))


def trajectory_error(
    estimate: Trajectory,
    reference: Trajectory,
    *,
    max_diff: float = MAX_DIFF,
    delta: float = DELTA,
) -> TrajectoryScore:
    """ATE and RPE of ``estimate`` against ``reference`` (see the module's note).

    Raises
    ------
    TrajectoryError
        If fewer than 2 poses match in time (naming both sources).
    """
    i, j = match_times(estimate.times, reference.times, max_diff)
    if len(i) < 2:
        raise TrajectoryError(
            f"{estimate.source}: {len(i)} of its {len(estimate.times)} poses within "
            f"{max_diff * 1000:g} ms of a pose of {reference.source}; 2 are needed"
        )
    est, ref = estimate.poses[i], reference.poses[j]
    motion = align_se2(est[:, :2], ref[:, :2])
    aligned = _moved(est, motion)
    ate = np.linalg.norm(aligned[:, :2] - ref[:, :2], axis=1)
    turn = np.remainder(aligned[:, 2] - ref[:, 2] + np.pi, 2 * np.pi) - np.pi
    first, second = _path_pairs(ref[:, :2], delta)
    rpe = rpe_turn = np.zeros(0)
    if len(first):
        q, p = _relative(ref, first, second), _relative(est, first, second)
        # E = Q_rel^-1 P_rel: the estimate's relative pose in the reference's.
        c, s = np.cos(q[:, 2]), np.sin(q[:, 2])
        d = p[:, :2] - q[:, :2]
        rpe = np.hypot(c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1])
        rpe_turn = np.remainder(p[:, 2] - q[:, 2] + np.pi, 2 * np.pi) - np.pi
    some = bool(len(rpe))
    return TrajectoryScore(
        estimate=estimate.source,
        reference=reference.source,
        estimate_poses=len(estimate.times),
        reference_poses=len(reference.times),
        matched=len(i),
        max_diff=max_diff,
        estimate_steps_back=estimate.steps_back,
        reference_steps_back=reference.steps_back,
        alignment=motion,
        ate_rmse=_rms(ate),
        ate_mean=float(ate.mean()),
        ate_median=float(np.median(ate)),
        ate_max=float(ate.max()),
        ate_rotation_rmse_deg=math.degrees(_rms(turn)),
        path_length=float(np.linalg.norm(np.diff(ref[:, :2], axis=0), axis=1).sum()),
        delta=delta,
        rpe_pairs=len(rpe),
        rpe_rmse=_rms(rpe) if some else None,
        rpe_mean=float(rpe.mean()) if some else None,
        rpe_max=float(rpe.max()) if some else None,
        rpe_rotation_rmse_deg=math.degrees(_rms(rpe_turn)) if some else None,
    )
