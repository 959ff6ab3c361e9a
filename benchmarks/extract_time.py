"""Median time of one ``Extractor`` call, and of ``Extractor.batch`` per scan, on simulated
481-beam and 181-beam scans.

    python benchmarks/extract_time.py [--scenes 50] [--repeats 20]

481 beams: the SICK TiM571 preset (160 deg at 1/3 deg, the paper's sensor). 181 beams: the
SICK LMS 1 deg preset widened to 181 beams (-90..+90 deg). Realistic noise, seeded scenes; each
scan is extracted ``repeats`` times after a warm-up and the median of all calls is printed.
Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import time

from scanlines import Extractor
from scanlines.sim import get_sensor, random_scene


def sensors():
    lms181 = dataclasses.replace(get_sensor("lms_1deg"), n_beams=181, angle_min=-math.pi / 2)
    return {"481 beams (tim571)": get_sensor("tim571"), "181 beams (lms, 181 beams)": lms181}


def median_us(extractor: Extractor, scans, repeats: int) -> float:
    for scan in scans[:5]:
        extractor(scan)
    samples = []
    for scan in scans:
        for _ in range(repeats):
            start = time.perf_counter()
            extractor(scan)
            samples.append(time.perf_counter() - start)
    return 1e6 * statistics.median(samples)


def batch_us(extractor: Extractor, scans, repeats: int) -> float:
    """Median over repeats of one ``batch`` call over all scans, per scan."""
    first = scans[0]
    stack = [s.ranges for s in scans]
    args = (first.angle_min, first.angle_increment, first.range_min, first.range_max)
    extractor.batch(stack[:5], *args)
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        extractor.batch(stack, *args)
        samples.append((time.perf_counter() - start) / len(scans))
    return 1e6 * statistics.median(samples)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=50)
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    for label, sensor in sensors().items():
        scans = [random_scene(s, sensor).scan(s).scan for s in range(args.scenes)]
        for preset in (None, "paper"):
            extractor = Extractor(preset=preset)
            us = median_us(extractor, scans, args.repeats)
            batch = batch_us(extractor, scans, args.repeats)
            print(
                f"{label:28s} {preset or 'default':8s} median {us:8.0f} us/call, "
                f"batch {batch:8.0f} us/scan ({1e6 / batch:,.0f} scans/s)"
            )


if __name__ == "__main__":
    main()
