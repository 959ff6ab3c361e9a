"""`localize` on a raw log against corrected keyframes: tracking, global localisation, kidnapping.

    python tools/benchmarks/global_localisation.py RAW --reference CORRECTED --map MAP.json \
        --initial-pose T,X,Y,YAW [--parts tracking slices kidnap] [--slices 20 --length 400] \
        [--sides]

The raw log's scans are read once into memory. Each corrected keyframe is matched to the
raw scan nearest in time (within 10 ms); a keyframe is *covered* when at least 30 % of that
scan's returns lie within 5 cm of a map line at the keyframe's corrected pose. Errors are
in the map's frame, no alignment.

* ``tracking``: ``localize`` from the initial pose over the whole log: RMSE over the covered
  keyframes, RMSE and max over all, the scans declared lost.
* ``slices``: ``localize`` without an initial pose on ``--slices`` slices of ``--length``
  scans, starting at scans spread evenly over the log among those whose nearest keyframe
  is covered: the error at the first keyframe ``--settle`` scans or more into the slice
  (a success: found, within 0.3 m and 5 deg), the scans until found, and every keyframe
  reported found (not ``lost``) more than 1 m off.
* ``kidnap``: from scan ``--kidnap`` on the odometry jumps 5 m along the robot's heading and
  turns 90 deg: the scan declared lost, the scan found again, the errors after.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from scanlines.evaluation.trajectory import load_trajectory
from scanlines.geometry.poses import compose, relative_pose
from scanlines.geometry.transform import points_to_world
from scanlines.io import open_log
from scanlines.map.align import nearest_segments
from scanlines.map.filter import FilterSettings
from scanlines.map.localize import localize, read_line_map

MATCH = 0.01
#: The filter's settings of every run (``--sides``).
SETTINGS = [FilterSettings()]
COVERED_SHARE, COVERED_DISTANCE = 0.3, 0.05


def keyframes(scans, reference, frame, lines):
    """Per keyframe: the raw scan's position, its pose in the map's frame, covered or not."""
    times = np.array([np.nan if s.timestamp is None else s.timestamp for _, s in scans])
    order = np.argsort(times)
    rows = []
    for t, pose in zip(reference.times, reference.poses, strict=True):
        k = np.searchsorted(times[order], t)
        near = [order[j] for j in (k - 1, k) if 0 <= j < len(order)]
        if not near:
            continue
        best = min(near, key=lambda p: abs(times[p] - t))
        if abs(times[best] - t) > MATCH:
            continue
        local = frame.pose(tuple(pose))
        scan = scans[best][1]
        world = points_to_world(scan.points[scan.valid], local)
        distance = nearest_segments(world, lines.start, lines.end)[0]
        covered = bool(np.mean(distance <= COVERED_DISTANCE) >= COVERED_SHARE)
        rows.append((int(best), local, covered))
    return rows


def errors(run, frames, positions):
    """Per keyframe of ``frames`` whose scan ``run`` tracked: (position, metres, degrees,
    status)."""
    by_index = {t.index: t for t in run.tracked}
    out = []
    for p, truth, covered in frames:
        record = by_index.get(positions[p])
        if record is None:
            continue
        d = math.hypot(record.pose[0] - truth[0], record.pose[1] - truth[1])
        turn = abs(math.degrees(math.remainder(record.pose[2] - truth[2], 2 * math.pi)))
        out.append((p, d, turn, record.status, covered))
    return out


def tracking(scans, lines, frame, initial, frames, positions):
    started = time.perf_counter()
    run = localize(iter(scans), lines, frame, initial, settings=SETTINGS[0])
    seconds = time.perf_counter() - started
    rows = errors(run, frames, positions)
    d = np.array([r[1] for r in rows])
    covered = np.array([r[4] for r in rows])
    rmse = lambda v: float(np.sqrt(np.mean(v**2))) if len(v) else math.nan  # noqa: E731
    print(f"tracking: {len(rows)} keyframes, {int(covered.sum())} covered; RMSE covered "
          f"{rmse(d[covered]):.4f} m, RMSE all {rmse(d):.4f} m, max all {d.max():.3f} m, "
          f"within 0.3 m {int((d <= 0.3).sum())}; lost at {run.lost_at}, found at "
          f"{run.found_at}; {len(scans) / seconds:.0f} scans/s (in memory)")  # fmt: skip
    worst = np.argsort(-d)[:5]
    print("  worst:", [(positions[rows[k][0]], round(float(d[k]), 3), rows[k][3]) for k in worst])


def slice_starts(frames, count: int, length: int, total: int):
    """``count`` scan positions spread evenly over those whose nearest keyframe is covered."""
    frame_positions = np.array([p for p, _, _ in frames])
    frame_covered = np.array([c for _, _, c in frames])
    candidates = []
    for p in range(0, total - length + 1):
        nearest = int(np.argmin(np.abs(frame_positions - p)))
        if frame_covered[nearest]:
            candidates.append(p)
    pick = np.linspace(0, len(candidates) - 1, count).round().astype(int)
    return [candidates[k] for k in pick]


def slices(scans, lines, frame, frames, positions, count, length, settle):
    successes, wrong = 0, 0
    for start in slice_starts(frames, count, length, len(scans)):
        part = scans[start : start + length]
        run = localize(iter(part), lines, frame, None, settings=SETTINGS[0])
        rows = [r for r in errors(run, frames, positions) if start <= r[0] < start + length]
        after = [r for r in rows if r[0] >= start + settle]
        found = next((k for k, t in enumerate(run.tracked) if t.status != "lost"), None)
        bad = [r for r in rows if r[3] != "lost" and r[1] > 1.0]
        wrong += len(bad)
        if not after:
            print(f"slice {start}: no keyframe {settle} scans in")
            continue
        p, d, turn, status, covered = after[0]
        ok = status != "lost" and d <= 0.3 and turn <= 5.0
        successes += ok
        print(f"slice {start}: keyframe at scan {p} ({p - start} in, covered {covered}): "
              f"{d:.3f} m {turn:.1f} deg, {status}; found after {found} scans; "
              f"{len(bad)} keyframes found more than 1 m off"
              + ("" if ok else "  <- miss"))  # fmt: skip
    print(f"slices: {successes} of {count} within 0.3 m and 5 deg; {wrong} keyframes reported "
          "found more than 1 m off")  # fmt: skip


def kidnap(scans, lines, frame, initial, frames, positions, at: int):
    jump = (5.0, 0.0, math.pi / 2)
    before = scans[at - 1][1].pose

    def odometry(index, scan):
        if scan.pose is None or index < positions[at]:
            return scan.pose
        return compose(compose(before, jump), relative_pose(before, scan.pose))

    run = localize(iter(scans), lines, frame, initial, poses=odometry, settings=SETTINGS[0])
    lost = [a for a in run.lost_at if a >= positions[at]]
    found = [b for b in run.found_at if lost and b > lost[0]]
    rows = errors(run, frames, positions)
    after = [r for r in rows if found and r[0] >= found[0]]
    bad = [r for r in rows if r[3] != "lost" and r[1] > 1.0 and r[0] >= at]
    print(
        f"kidnap at scan {positions[at]}: lost at {lost[:1]}, found at {found[:1]}"
        + (f" ({found[0] - positions[at]} scans after the jump)" if found else "")
        + f"; lost before the jump at {[a for a in run.lost_at if a < positions[at]]}"
    )
    if after:
        d = np.array([r[1] for r in after])
        print(
            f"  after found: {len(after)} keyframes, first {after[0][1]:.3f} m "
            f"{after[0][2]:.1f} deg, RMSE {float(np.sqrt(np.mean(d**2))):.3f} m, "
            f"max {d.max():.3f} m; {len(bad)} keyframes reported not lost more than 1 m "
            f"off: {[(positions[r[0]], round(r[1], 2), r[3]) for r in bad]}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("raw")
    parser.add_argument("--reference", required=True)
    parser.add_argument("--map", required=True)
    parser.add_argument("--initial-pose", required=True)
    parser.add_argument("--parts", nargs="+", default=["tracking", "slices", "kidnap"])
    parser.add_argument("--slices", type=int, default=20)
    parser.add_argument("--length", type=int, default=400)
    parser.add_argument("--settle", type=int, default=50)
    parser.add_argument("--kidnap", type=int, default=2750)
    parser.add_argument("--sides", action="store_true", help="as `localize --sides`")
    args = parser.parse_args()
    values = [float(v) for v in args.initial_pose.split(",")]
    initial = (values[0], tuple(values[1:]))
    lines, frame = read_line_map(args.map)
    SETTINGS[0] = FilterSettings(sides=args.sides)
    with open_log(args.raw) as reader:
        scans = list(reader.enumerate())
    positions = [index for index, _ in scans]
    frames = keyframes(scans, load_trajectory(args.reference), frame, lines)
    if "tracking" in args.parts:
        tracking(scans, lines, frame, initial, frames, positions)
    if "slices" in args.parts:
        slices(scans, lines, frame, frames, positions, args.slices, args.length, args.settle)
    if "kidnap" in args.parts:
        kidnap(scans, lines, frame, initial, frames, positions, args.kidnap)


if __name__ == "__main__":
    main()
