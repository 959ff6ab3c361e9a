"""Median time of one ``Extractor`` call, and of ``Extractor.batch`` per scan, on simulated
481-beam and 181-beam scans.

    python tools/benchmarks/extract_time.py [--scenes 50] [--repeats 20]

481 beams: the SICK TiM571 preset (160 deg at 1/3 deg, the paper's sensor). 181 beams: the
SICK LMS 1 deg preset widened to 181 beams (-90..+90 deg). Realistic noise, seeded scenes;
``repeats`` timed passes over the scans by the project's one timing rule
(``scanlines.bench.timing``: every timed call right after an untimed call on the same
scan), and the median of all timed calls is printed. Speed is measured here, never asserted in
tests.
"""

from __future__ import annotations

import argparse
import dataclasses
import math

import numpy as np

from scanlines import Extractor
from scanlines.bench.timing import time_calls
from scanlines.sim import get_sensor, random_scene


def sensors():
    lms181 = dataclasses.replace(get_sensor("lms_1deg"), n_beams=181, angle_min=-math.pi / 2)
    return {"481 beams (tim571)": get_sensor("tim571"), "181 beams (lms, 181 beams)": lms181}


def median_us(extractor: Extractor, scans, repeats: int) -> float:
    """Median time of one call, over ``repeats`` passes over ``scans``."""
    timed = time_calls({"call": extractor}, scans, repeats)["call"]
    return float(np.median(timed.samples_ns)) / 1000.0


def batch_us(extractor: Extractor, scans, repeats: int) -> float:
    """Median over repeats of one ``batch`` call over all scans, per scan."""
    first = scans[0]
    stack = np.stack([s.ranges for s in scans])
    args = (first.angle_min, first.angle_increment, first.range_min, first.range_max)
    timed = time_calls({"batch": lambda rows: extractor.batch(rows, *args)}, [stack], repeats)
    return float(np.median(timed["batch"].samples_ns)) / 1000.0 / len(scans)


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
