"""Huge scans cost time and memory linear in their beams, for every method.

Three scans of one full turn (``tools/benchmarks/large_scans.py``): a noise-free arc (every
point on one circle: the worst case of splitting at the worst residual), a room with
1 cm noise, and uniform random ranges (the worst case of the consensus methods). Each
method runs in a fresh process, so its peak memory is its own. CI uses 200,000 beams;
``pytest --long`` the issue's 10^6. Time is judged by a ratio measured in that one process:
the processor time of the huge scan over that of a scan of a tenth of its beams, timed just
before and after it. Linear cost gives 10, n log n about 12, the quadratic costs this guards
against 100; a machine's load slows both scans alike, so the suite passes on a busy machine
(the bound of 10 s once failed at a load of 9). Memory keeps the issue's bound of 1 GB.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import scanlines
from scanlines import Extractor, Scan

pytestmark = pytest.mark.slow  # million-beam scans

BENCHMARK = Path(__file__).parents[1] / "tools" / "benchmarks" / "large_scans.py"
SCALE, RATIO, MEGABYTES = 10, 30.0, 1024.0


@pytest.mark.parametrize("method", scanlines.method_names())
def test_a_huge_scan_costs_linear_time_and_bounded_memory(method, request) -> None:
    beams = 1_000_000 if request.config.getoption("--long") else 200_000
    for case in ("arc", "room", "random"):
        command = [sys.executable, str(BENCHMARK), "--one", method, case, "--beams", str(beams)]
        command += ["--scale", str(SCALE)]
        out = subprocess.run(command, capture_output=True, text=True, timeout=300, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        assert row["ratio"] < RATIO, (case, row)
        assert row["peak_mb"] < MEGABYTES, (case, row)


def test_an_arc_becomes_a_chain_of_segments() -> None:
    """The residual split cuts an arc where it bends from its chord: the chain covers the
    arc (it used to lose the arc's ends one point at a time)."""
    beams = 3600
    scan = Scan(np.full(beams, 5.0), -np.pi, 2 * np.pi / beams)
    result = Extractor("adaptive", max_residual=0.01)(scan)
    covered = sum(segment.n_points for segment in result.segments)
    assert covered > 0.95 * beams
    # the fitted line lies between an arc and its chord: residuals up to half the sagitta
    sagitta = [5.0 * (1 - np.cos(s.n_points * np.pi / beams)) for s in result.segments]
    assert max(sagitta) < 2 * 0.01 * 1.1
