"""Time and peak memory of every method on very large scans (10^6 beams by default).

    python tools/benchmarks/large_scans.py [--beams 1000000] [-m adaptive] [--case arc]

Three scans, each over one full turn: a noise-free arc of radius 5 m (every beam on one
circle), a 10 m x 6 m room seen from off its centre with 1 cm range noise, and uniform
random ranges in [0.1, 30] m. Each method and scan runs in a fresh process (its kernels
loaded from the cache first, on a small scan), and the process's peak resident memory is
read after the call, so one case's allocations do not hide another's. Printed: seconds
of the one call and peak memory in MB. The issue's target is under 10 s and 1 GB for
every method and scan.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CASES = ("arc", "room", "random")


def make_ranges(case: str, beams: int):
    import numpy as np

    rng = np.random.default_rng(0)
    bearings = np.linspace(-np.pi, np.pi, beams, endpoint=False)
    if case == "arc":
        return np.full(beams, 5.0)
    if case == "random":
        return rng.uniform(0.1, 30.0, beams)
    # a 10 x 6 m room, the sensor at (1, 0.5) from its centre: distance to the walls
    x0, y0, half_w, half_h = 1.0, 0.5, 5.0, 3.0
    c, s = np.cos(bearings), np.sin(bearings)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (half_w - x0) / c, (-half_w - x0) / c)
        ty = np.where(s > 0, (half_h - y0) / s, (-half_h - y0) / s)
    return np.minimum(np.abs(tx), np.abs(ty)) + rng.normal(0.0, 0.01, beams)


def measure(method: str, case: str, beams: int, scale: int = 0) -> dict:
    """In this process: one call on a small scan first (the bearing tables, lazy imports),
    then time one call on the large scan.

    With ``scale``, also the scan of ``beams // scale`` beams before and after the large one:
    ``ratio`` is the large call's processor time over the mean of the small ones', measured
    in one process (a machine's load slows both alike; linear cost gives ``scale``)."""
    import math
    import resource
    import time

    from scanlines import Extractor, Scan

    extractor = Extractor(method)
    extractor(Scan(make_ranges("room", 100), angle_min=-math.pi, angle_increment=0.0628))

    def timed(n: int):
        ranges = make_ranges(case, n)
        scan = Scan(ranges, angle_min=-math.pi, angle_increment=2 * math.pi / n, range_max=40.0)
        started, cpu = time.perf_counter(), time.process_time()
        result = extractor(scan)
        return time.perf_counter() - started, time.process_time() - cpu, result

    small = [timed(beams // scale)[1]] if scale else []
    seconds, cpu_seconds, result = timed(beams)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    row = {"seconds": seconds, "peak_mb": peak_mb, "segments": len(result.segments)}
    if scale:
        small.append(timed(beams // scale)[1])
        row["ratio"] = cpu_seconds / max(sum(small) / len(small), 1e-6)
        row["cpu_seconds"], row["small_cpu_seconds"] = cpu_seconds, small
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--beams", type=int, default=1_000_000)
    parser.add_argument("-m", "--method", action="append")
    parser.add_argument("--case", action="append", choices=CASES)
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)  # method, case: the child
    parser.add_argument("--scale", type=int, default=0, help=argparse.SUPPRESS)  # the ratio's
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.one[0], args.one[1], args.beams, args.scale)))
        return
    from scanlines import method_names

    print(f"{'method':<16} {'case':<7} {'seconds':>8} {'peak MB':>8} {'segments':>9}")
    for method in args.method or method_names():
        for case in args.case or CASES:
            command = [sys.executable, __file__, "--one", method, case, "--beams", str(args.beams)]
            try:
                out = subprocess.run(
                    command, capture_output=True, text=True, timeout=args.timeout, check=True
                )
                row = json.loads(out.stdout.strip().splitlines()[-1])
                print(
                    f"{method:<16} {case:<7} {row['seconds']:>8.2f} {row['peak_mb']:>8.0f} "
                    f"{row['segments']:>9}",
                    flush=True,
                )
            except subprocess.TimeoutExpired:
                print(f"{method:<16} {case:<7} {'> ' + str(args.timeout):>8}", flush=True)
            except subprocess.CalledProcessError as error:
                print(f"{method:<16} {case:<7} failed: {error.stderr.strip()[-200:]}", flush=True)


if __name__ == "__main__":
    main()
