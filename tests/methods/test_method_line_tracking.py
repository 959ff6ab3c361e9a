"""Line tracking: grow a line point by point; its corner lag and its lack of merging."""

from __future__ import annotations

import numpy as np
import pytest
from test_method_common import SIGMA, room_corners, room_scan, simulated_summary

from scanlines import Scan, extract
from scenes import scan_of

# Measured on the seeded set (defaults, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.444, segment TruePos 0.609 (corner F1 0.293)
#   lms_1deg: breakpoint F1 0.428, segment TruePos 0.846 (corner F1 0.300)


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.42, 0.58), ("lms_1deg", 0.40, 0.82)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("line_tracking", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


@pytest.mark.parametrize("seed", range(3))
def test_a_segment_runs_past_its_corner(seed):
    """The paper (Electronics 2022, sec. 1): points of the next wall go to the current line.

    Past a right-angle corner the next returns leave the line by one spacing each,
    so the segment ends only when one is ``track_distance`` off (about 4 returns at
    2 m and 1/3 deg, 10 cm).
    """
    scan = room_scan(seed)
    result = extract(scan, "line_tracking")
    late = result.last[:4] - np.array(room_corners(scan))
    assert np.all(late >= 2)
    assert np.all(late <= 6)
    tighter = extract(scan, "line_tracking", track_distance=0.04)
    assert np.all(tighter.last[:4] - np.array(room_corners(scan)) < late)


def test_a_wall_cut_by_one_stray_return_stays_cut():
    scan = scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=SIGMA, seed=0)
    ranges = scan.ranges.copy()
    ranges[150] -= 0.2  # within the 0.3 m jump: same cluster
    result = extract(Scan(ranges, scan.angle_min, scan.angle_increment), "line_tracking")
    assert result.last[0] == 149
    assert result.first[1] == 150
    assert len(result) == 2
    assert result.breakpoints.size == 0
    assert result.corners.size == 0
