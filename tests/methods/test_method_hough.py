"""Hough transform: the accumulator, its resolution, the vote threshold."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_method_common import (
    assert_room_walls,
    room_corners,
    room_scan,
    simulated_summary,
)

from scanlines import extract
from scanlines.methods.hough import Accumulator
from scenes import returns_of

# Measured on the seeded set (defaults: whole scan, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.850, segment TruePos 0.689 (corner F1 0.455)
#   lms_1deg: breakpoint F1 0.768, segment TruePos 0.962 (corner F1 0.600)


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.82, 0.66), ("lms_1deg", 0.74, 0.93)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("hough", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


def test_every_point_votes_once_per_angle_and_leaves_its_votes():
    returns = returns_of(room_scan(0))
    n = returns.index.shape[0]
    member = np.ones(n, dtype=bool)
    acc = Accumulator(
        returns, member, rho_resolution=0.02, angle_resolution=math.radians(1.0), min_votes=5
    )
    assert acc.angles.size == 180
    assert acc.votes.sum() == n * 180
    acc.remove(np.arange(100))
    acc.remove(np.arange(50, 150))  # the first 100 only once
    assert acc.votes.sum() == (n - 150) * 180
    rho, alpha = acc.best_line(member)
    # the strongest line is a wall: 2 m from the sensor, axis-aligned in the sensor frame
    # (the returns are in the scan's frame, turned by angle_min = -170 deg)
    assert abs(rho) == pytest.approx(2.0, abs=0.02)
    turned = alpha + math.radians(-170.0)
    assert math.remainder(turned, math.pi / 2) == pytest.approx(0.0, abs=math.radians(1.0))


def test_a_coarse_accumulator_still_gives_exact_lines():
    scan = room_scan(1)
    result = extract(scan, "hough", angle_resolution=3.0, rho_resolution=0.05)
    assert len(result) == 5
    assert np.all(np.abs(result.corners - room_corners(scan)) <= 1)
    assert_room_walls(result)


def test_no_peak_reaches_an_impossible_vote_count():
    scan = room_scan(0)
    assert len(extract(scan, "hough", min_votes=len(scan) + 1)) == 0
