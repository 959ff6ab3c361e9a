"""How well a corrected log's own scans agree with its poses: pairs of keyframes aligned.

    python tools/benchmarks/reference_pairs.py CORRECTED [--until 1088.7] [--radius 1.0]

Each keyframe (up to ``--until`` seconds) is paired with the nearest earlier keyframe within
``--radius`` metres that is at least ``--gap`` seconds older (another pass); the later scan's
returns are aligned to the earlier scan and its ``--window`` neighbours either side, placed by
the corrected poses, from the corrected relative pose, with the loop closer's alignment and
quality checks (:mod:`scanlines.map.loops`). Prints how far the alignment moved the corrected
relative pose (median, RMS, max; mm and degrees) over the pairs it accepts.

Then the keyframes as a pose graph of their own scans: each keyframe aligned to the one before
(the corrected relative pose where that fails), the pairs above as closures, with the loop
closer's weights, optimised from the corrected poses; prints the optimum's ATE against the
corrected poses (SE(2) aligned): how far the corrected log is from what its own scans say.
Reads the log given, nothing else.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np


def read(path: Path, until: float):
    from scanlines.geometry.registration import line_target
    from scanlines.io import open_log
    from scanlines.map.loops import _Node

    nodes, poses, times = [], [], []
    with open_log(path) as reader:
        for _, scan in reader.enumerate():
            if scan.timestamp is None or scan.timestamp > until or scan.pose is None:
                continue
            points = np.array(scan.points[scan.valid], dtype=np.float64)
            nodes.append(_Node(len(nodes), line_target(scan), points))
            poses.append(scan.pose)
            times.append(scan.timestamp)
    return nodes, np.array(poses), np.array(times)


def aligned(nodes, poses, o: int, q: int, window: int):
    """The alignment of keyframe ``q`` to ``o`` and its neighbours, or None if poor."""
    from scanlines.map.loops import LoopSettings, _register, _submap

    s = LoopSettings()
    fit = _register(nodes[q].points, _submap(o, poses, nodes, window), poses[o], poses[q])
    if fit is None or fit.inlier_fraction < s.min_inliers:
        return None
    return None if fit.rms > s.max_rms or fit.least < s.least else fit


def pairs(nodes, poses, times, args) -> list:
    """``(o, q, fit)`` of each keyframe aligned to an earlier pass's."""
    found = []
    for q in range(len(nodes)):
        older = np.flatnonzero(times < times[q] - args.gap)
        if not len(older):
            continue
        d = np.hypot(*(poses[older, :2] - poses[q, :2]).T)
        if d.min() <= args.radius:
            o = int(older[np.argmin(d)])
            fit = aligned(nodes, poses, o, q, args.window)
            if fit is not None:
                found.append((o, q, fit))
    return found


def report_pairs(found, poses, times, worst: int) -> None:
    from scanlines.geometry.poses import compose, relative_pose

    rows = []
    for o, q, fit in found:
        truth = relative_pose(tuple(poses[o]), tuple(poses[q]))
        moved = compose(tuple(poses[o]), fit.pose)
        turn = abs(math.degrees(math.remainder(fit.pose[2] - truth[2], 2 * math.pi)))
        rows.append((math.hypot(moved[0] - poses[q][0], moved[1] - poses[q][1]), turn, o, q))
    m, t = np.array([r[0] for r in rows]), np.array([r[1] for r in rows])
    print(
        f"{len(m)} pairs aligned: moved median {1000 * np.median(m):.1f} mm, RMS "
        f"{1000 * math.sqrt(np.mean(m**2)):.1f} mm, max {1000 * m.max():.1f} mm; turned median "
        f"{np.median(t):.2f} deg, RMS {math.sqrt(np.mean(t**2)):.2f} deg, max {t.max():.2f}"
    )
    for move, _, o, q in sorted(rows, reverse=True)[:worst]:
        print(f"  {1000 * move:.0f} mm: keyframes at {times[o]:.1f} s and {times[q]:.1f} s")


def own_optimum(nodes, poses, found) -> None:
    """The keyframes' graph of their own scans, optimised; its ATE against the poses."""
    from scanlines.evaluation.trajectory import _moved, align_se2
    from scanlines.geometry.poses import relative_pose
    from scanlines.map.loops import LoopSettings
    from scanlines.map.posegraph import Edge, PoseGraph, optimise

    s = LoopSettings()
    track = np.diag([1 / s.edge_floor**2] * 2 + [1 / s.edge_turn_floor**2])
    graph, fallback = PoseGraph(np.array(poses, dtype=np.float64)), 0
    for k in range(1, len(nodes)):
        fit = aligned(nodes, poses, k - 1, k, 0)
        fallback += fit is None
        z = relative_pose(tuple(poses[k - 1]), tuple(poses[k])) if fit is None else fit.pose
        graph.add(Edge(k - 1, k, z, track))
    for o, q, fit in found:
        graph.add(Edge(o, q, fit.pose, s.closure_information(), "loop"))
    best = optimise(graph).poses
    moved = _moved(best, align_se2(best[:, :2], poses[:, :2]))
    ate = np.linalg.norm(moved[:, :2] - poses[:, :2], axis=1)
    print(
        f"own graph ({len(nodes) - 1 - fallback} of {len(nodes) - 1} consecutive keyframes "
        f"aligned, {len(found)} closures): ATE of its optimum against the corrected poses "
        f"RMSE {1000 * math.sqrt(np.mean(ate**2)):.1f} mm, max {1000 * ate.max():.1f} mm"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    parser.add_argument("--until", type=float, default=1088.7)
    parser.add_argument("--radius", type=float, default=1.0)
    parser.add_argument("--gap", type=float, default=30.0)
    parser.add_argument("--window", type=int, default=2)
    parser.add_argument("--worst", type=int, default=10, help="List the pairs moved most.")
    args = parser.parse_args()
    nodes, poses, times = read(args.log, args.until)
    found = pairs(nodes, poses, times, args)
    report_pairs(found, poses, times, args.worst)
    own_optimum(nodes, poses, found)


if __name__ == "__main__":
    main()
