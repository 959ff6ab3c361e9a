"""Iterative end-point fit: chord splits, the split threshold, fixed-jump clusters."""

from __future__ import annotations

import numpy as np
import pytest
from test_method_common import simulated_summary

from scanlines import extract
from scenes import scan_of

# Measured on the seeded set (defaults, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.444, segment TruePos 0.646 (corner F1 0.600)
#   lms_1deg: breakpoint F1 0.428, segment TruePos 0.933 (corner F1 0.667)
# The fixed jump of 0.3 m cuts at every spurious return and grazing wall: most
# breakpoints found are false.


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.42, 0.62), ("lms_1deg", 0.40, 0.90)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("iepf", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


def noisy_wall(seed: int):
    return scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=0.01, seed=seed)


def test_a_threshold_near_the_noise_over_segments_a_wall():
    """The paper (Electronics 2022, Fig. 10a): IEPF's fixed threshold cuts a noisy wall."""
    for seed in range(3):
        scan = noisy_wall(seed)
        assert len(extract(scan, "iepf")) == 1
        split = extract(scan, "iepf", split_distance=0.025)
        assert len(split) >= 3
        assert split.breakpoints.size == 0


def slanted_wall():
    """A wall at y = 2 from x = 4 to 10, seen at 63-79 deg incidence, 1 deg beams."""
    return scan_of([((4.0, 2.0), (10.0, 2.0))], fov_deg=20, step_deg=1.0, sigma=0.005, start_deg=8)


def test_the_fixed_jump_cuts_a_slanted_wall_that_abd_keeps():
    scan = slanted_wall()
    fixed = extract(scan, "iepf")
    assert fixed.breakpoints.size >= 2
    abd = extract(scan, "iepf", breakpoints="abd")
    assert abd.breakpoints.size == 0
    assert len(abd) == 1
    assert np.isclose(abd.segments[0].rho, 2.0, atol=0.01)
