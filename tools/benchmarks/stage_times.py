"""Where the adaptive kernel spends its time: each stage timed inside it, one simulated scan.

    python tools/benchmarks/stage_times.py [--sensor tim571] [--seed 3] [--repeats 300]

The kernel is C++ (``cpp/scanlines/methods/adaptive.cpp``): its stages are not callable on
their own, so ``scanlines._core.adaptive_stage_seconds`` runs the whole kernel and times
each stage inside it with a steady clock (about 50 ns of clock reads per stage). That
function exists only in a build made for this tool (product builds carry no timing code),
in a virtual environment of its own::

    python -m venv /tmp/stages && . /tmp/stages/bin/activate
    pip install scikit-build-core nanobind
    pip install --no-build-isolation -Ccmake.define.SCANLINES_STAGE_TIMES=ON .

The timed kernel makes adaptive_scan's calls in its order; the tool checks that its table is
``adaptive_stack``'s. The stages add up to the kernel without its call overhead (the
conversion of the arguments and the boxing of the table). The whole call and the whole
kernel are timed from Python by the package's one timing rule
(:func:`scanlines.bench.timing.time_calls`); every row is the median of ``repeats`` samples,
passes interleaved. Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse

import numpy as np

from scanlines import Extractor, _core
from scanlines.bench.timing import time_calls
from scanlines.scan import is_full_circle
from scanlines.sim import random_scene

WHOLE = "whole kernel"
STAGES = "stages"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sensor", default="tim571")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=300)
    args = parser.parse_args()
    if not hasattr(_core, "adaptive_stage_seconds"):
        raise SystemExit(
            "stage_times.py: this build of scanlines has no stage timing; build one with "
            "-Ccmake.define.SCANLINES_STAGE_TIMES=ON (see this script's docstring)"
        )
    scan = random_scene(args.seed, args.sensor).scan(args.seed).scan
    extractor = Extractor()
    method = extractor._method
    step = abs(scan.angle_increment)
    local = scan.angle_increment * np.arange(len(scan))
    arguments = (
        np.ascontiguousarray(scan.ranges, dtype=np.float64)[np.newaxis],
        np.ascontiguousarray(scan.valid, dtype=np.bool_)[np.newaxis],
        np.cos(local),
        np.sin(local),
        step,
        is_full_circle(len(scan), scan.angle_increment),
        scan.angle_min,
        tuple(method.noise),
        *method.arguments,
    )
    stage_seconds: list[dict[str, float]] = []

    def stages() -> None:
        stage_seconds.append(_core.adaptive_stage_seconds(*arguments)[0])

    timed_table = _core.adaptive_stage_seconds(*arguments)[1]
    for timed, plain in zip(timed_table, _core.adaptive_stack(*arguments), strict=True):
        if not np.array_equal(timed, plain, equal_nan=True):
            raise SystemExit("stage_times.py: the timed kernel's table is not adaptive_stack's")

    rows = {
        "whole call (Extractor)": lambda: extractor(scan),
        WHOLE: lambda: _core.adaptive_stack(*arguments),
        STAGES: stages,
    }
    timed = time_calls(
        {name: (lambda _, call=call: call()) for name, call in rows.items()}, [None], args.repeats
    )
    segments = len(extractor(scan))
    print(
        f"{args.sensor}, seed {args.seed}: {int(np.count_nonzero(scan.valid))} returns, "
        f"{segments} segments; median of {args.repeats} calls"
    )
    for name in (n for n in rows if n != STAGES):
        print(f"{name:32s} {np.median(timed[name].samples_ns) / 1000:8.1f} us")
    for name in stage_seconds[0]:
        median = np.median([seconds[name] for seconds in stage_seconds])
        print(f"  {name:30s} {median * 1e6:8.1f} us")


if __name__ == "__main__":
    main()
