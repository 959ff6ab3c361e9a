"""Line regression: sliding windows, their fidelity, overlapping runs."""

from __future__ import annotations

import pytest
from test_method_common import SIGMA, door_scene, room_scan, simulated_summary

from scanlines import extract
from scenes import scan_of

# Measured on the seeded set (defaults, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.444, segment TruePos 0.522 (corner F1 0.147)
#   lms_1deg: breakpoint F1 0.428, segment TruePos 0.808 (corner F1 0.526)
# At 1/3 deg a 9-return window spans 4-15 cm: on far and grazing walls its line
# is mostly noise, and the walls break into many short pieces.


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.42, 0.49), ("lms_1deg", 0.40, 0.78)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("line_regression", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


def test_a_wall_shorter_than_the_window_is_not_found():
    # a 7 cm post 2 m ahead: 7 returns, in front of the door scene
    walls = [*door_scene(), ((2.0, -0.035), (2.0, 0.035))]
    scan = scan_of(walls, fov_deg=100, step_deg=1 / 3, sigma=SIGMA, seed=0)
    post = [s for s in extract(scan, "line_regression", window=5).segments if s.rho < 2.5]
    assert len(post) == 1
    assert post[0].n_points == 7
    default = extract(scan, "line_regression")
    assert all(s.rho > 2.5 for s in default.segments)


def test_a_lax_fidelity_bound_merges_the_room():
    scan = room_scan(0)
    assert len(extract(scan, "line_regression", range_sigma=SIGMA, fidelity=8.0)) == 5
    lax = extract(scan, "line_regression", range_sigma=SIGMA, fidelity=1e6)
    assert len(lax) == 1  # every window is similar to its neighbours: one cluster, one line
    assert lax.corners.size == 0
