"""Loop closure on a raw log scored against a reference: ATE/RPE, closures against keyframes.

    python tools/benchmarks/loop_ate.py RAW --reference CORRECTED [--set NAME=VALUE ...]
        [--out DIR] [--scans 0:5505]

Runs what ``scanlines map RAW --align`` runs (the same extractor, sensor profile, tracker and
fusion settings; :class:`~scanlines.map.loops.LoopSettings` changed by ``--set``), then scores
the tracked and the optimised poses as ``scanlines eval trajectory`` does (matched within
10 ms, SE(2) aligned) and checks every accepted closure whose two scans both have a reference
pose within 10 ms against the reference's relative pose (0.3 m, 5 deg). Prints one JSON line;
``--out`` keeps the poses (TUM) and that line. Reads the logs given, nothing else.
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import resource
import tempfile
import time
from pathlib import Path

import numpy as np


def loop_settings(assignments: list[str]):
    from scanlines.map.loops import LoopSettings

    # Each setting's check reads the text as the command line gives it ("3", "0.02").
    return LoopSettings(**dict(item.split("=", 1) for item in assignments))


class _Recorder:
    """A LoopCloser that keeps what it was given, to replay closures on the same tracking."""

    def __init__(self, closer) -> None:
        self.closer, self.added = closer, []

    def __getattr__(self, name):
        return getattr(self.closer, name)

    def add(self, index, pose, covariance, scan=None, local=None) -> None:
        self.added.append((index, pose, covariance, scan, local))
        self.closer.add(index, pose, covariance, scan, local)


def replay(path: Path, loops):
    """The closures of a saved tracking (``--save``) with ``loops``: (build, result)."""
    from scanlines.map.loops import LoopCloser

    with open(path, "rb") as f:
        build, added = pickle.load(f)
    closer = LoopCloser(loops)
    for item in added:
        closer.add(*item)
    return build, closer.close()


def run(log: Path, scans: str | None, loops, save: Path | None = None):
    from scanlines.cli.maps import prepare
    from scanlines.io import open_log
    from scanlines.map import loopmap
    from scanlines.map.tracking import TrackSettings
    from scanlines.reader_options import ReaderOptions, parse_scans, select_scans

    options = ReaderOptions()
    prepared = prepare(log, options, None, None, None, None, None, None, None, scans)
    recorders, real = [], loopmap.LoopCloser

    def recording(settings):
        recorders.append(_Recorder(real(settings)))
        return recorders[-1]

    loopmap.LoopCloser = recording
    try:
        with open_log(log, options=options) as reader:
            indexed = select_scans(reader.enumerate(), parse_scans(scans))
            build, result = loopmap.build_closed_map(
                indexed, prepared["extractor"], poses=prepared["poses"],
                settings=prepared["settings"], track=TrackSettings(), loops=loops,
                source=str(log),
            )  # fmt: skip
    finally:
        loopmap.LoopCloser = real
    if save is not None:
        with open(save, "wb") as f:
            pickle.dump((build, recorders[0].added), f)
    return build, result


def score(records, frame, reference) -> dict:
    from scanlines.evaluation.trajectory import load_trajectory, trajectory_error
    from scanlines.map.poses import write_tum

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "poses.tum"
        timed = [r for r in records if r.timestamp is not None]
        write_tum(path, [(r.timestamp, frame.world_pose(r.pose)) for r in timed])
        s = trajectory_error(load_trajectory(path), reference)
    return {
        "ate_mm": round(1000 * s.ate_rmse, 1), "ate_max_mm": round(1000 * s.ate_max, 1),
        "ate_deg": round(s.ate_rotation_rmse_deg, 2), "rpe_mm": round(1000 * s.rpe_rmse, 1),
        "rpe_deg": round(s.rpe_rotation_rmse_deg, 2), "matched": s.matched,
    }  # fmt: skip


def closure_check(build, result, reference) -> dict:
    """Every accepted closure whose scans both have a reference pose within 10 ms."""
    from scanlines.evaluation.trajectory import match_times
    from scanlines.geometry.poses import relative_pose

    times = np.array([np.nan if r.timestamp is None else r.timestamp for r in build.tracked])
    errors = []
    for c in result.closures:
        ti, tj = times[c.node_i], times[c.node_j]
        a, ka = match_times(np.array([ti]), reference.times)
        b, kb = match_times(np.array([tj]), reference.times)
        if not len(a) or not len(b):
            continue
        truth = relative_pose(tuple(reference.poses[ka[0]]), tuple(reference.poses[kb[0]]))
        d = np.array(c.pose) - np.array(truth)
        turn = abs(math.degrees(math.remainder(d[2], 2 * math.pi)))
        errors.append((math.hypot(d[0], d[1]), turn))
    e = np.array(errors).reshape(-1, 2)
    bad = int(np.count_nonzero((e[:, 0] > 0.3) | (e[:, 1] > 5.0))) if len(e) else 0
    return {
        "checked": len(e), "outside_0.3m_5deg": bad,
        "max_mm": round(1000 * float(e[:, 0].max()), 1) if len(e) else None,
        "max_deg": round(float(e[:, 1].max()), 2) if len(e) else None,
    }  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    parser.add_argument("--reference", type=Path, required=True)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    parser.add_argument("--scans", default="0:5505")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--save", type=Path, help="Keep the tracking (pickle) for --replay.")
    parser.add_argument("--replay", type=Path, help="Close loops on a saved tracking only.")
    args = parser.parse_args()

    from scanlines.evaluation.trajectory import load_trajectory
    from scanlines.map.loopmap import closed_records

    loops = loop_settings(args.set)
    wall, cpu = time.perf_counter(), time.process_time()
    if args.replay:
        build, result = replay(args.replay, loops)
    else:
        build, result = run(args.log, args.scans, loops, args.save)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    reference = load_trajectory(args.reference)
    closed = closed_records(build, result)
    line = {
        "set": args.set, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
        "peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
        "tracked": score(build.tracked, build.frame, reference),
        "closed": score(closed, build.frame, reference),
        "closures": len(result.closures), "candidates": result.candidates,
        "refused": result.refused, "check": closure_check(build, result, reference),
        "lines": None if args.replay else len(build.line_map.lines()),
    }  # fmt: skip
    print(json.dumps(line))
    if args.out:
        from scanlines.map.tracked import write_tracked

        args.out.mkdir(parents=True, exist_ok=True)
        write_tracked(closed, build.frame, args.out / "poses.tum")
        (args.out / "result.json").write_text(json.dumps(line) + "\n")


if __name__ == "__main__":
    main()
