"""PDBS: Premebida and Nunes' distance rule, then IEPF splitting."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_method_common import simulated_set, simulated_summary

from scanlines import extract
from scenes import scan_of

# Measured on the seeded set (defaults, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.275, segment TruePos 0.565 (corner F1 0.558)
#   lms_1deg: breakpoint F1 0.320, segment TruePos 0.837 (corner F1 0.667)


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.25, 0.54), ("lms_1deg", 0.29, 0.81)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("pdbs", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


def test_is_iepf_with_the_pdbs_rule():
    for sim in simulated_set("tim571")[:5]:
        a = extract(sim.scan, "pdbs")
        b = extract(sim.scan, "iepf", breakpoints="pdbs")
        assert a.first.tolist() == b.first.tolist()
        assert a.breakpoints.tolist() == b.breakpoints.tolist()
        np.testing.assert_array_equal(a.lines, b.lines)


def test_the_threshold_follows_range_but_not_incidence():
    """The paper (Electronics 2022, Fig. 12a): PDBS over-segments a slanted wall."""
    # y = 2 m from x = 4 to 10 at 1 deg: 63-79 deg incidence. PDBS allows
    # C0 + C1 r = 0.1 m + 0.017 r, the returns are r dtheta / cos(incidence) apart.
    scan = scan_of([((4.0, 2.0), (10.0, 2.0))], fov_deg=20, step_deg=1.0, sigma=0.005, start_deg=8)
    cut = extract(scan, "pdbs")
    assert cut.breakpoints.size >= 2
    points = scan.points[scan.valid]
    gaps = np.hypot(*np.diff(points, axis=0).T)
    c1 = math.sqrt(2 * (1 - math.cos(math.radians(1.0))))
    limit = 0.1 + c1 * np.minimum(scan.ranges[scan.valid][:-1], scan.ranges[scan.valid][1:])
    assert np.count_nonzero(gaps >= limit) == cut.breakpoints.size
    kept = extract(scan, "pdbs", breakpoints="abd")
    assert kept.breakpoints.size == 0
