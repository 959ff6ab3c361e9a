"""Split-and-merge after laser_line_extraction: outliers, split on the fit, chi-square merge."""

from __future__ import annotations

import numpy as np
import pytest
from test_method_common import SIGMA, door_scene, room_scan, simulated_summary

from scanlines import Scan, extract
from scenes import scan_of

# Measured on the seeded set (defaults, 20 scenes per sensor):
#   tim571:   breakpoint F1 0.657, segment TruePos 0.590 (corner F1 0.176)
#   lms_1deg: breakpoint F1 0.660, segment TruePos 0.769 (corner F1 0.444)
# min_line_length = 0.5 m and min_line_points = 9 drop the scenes' short walls and
# box faces, and with them most corners.


@pytest.mark.parametrize(
    ("preset", "bp_f1", "true_pos"), [("tim571", 0.63, 0.57), ("lms_1deg", 0.63, 0.74)]
)
def test_seeded_simulated_set_floor(preset, bp_f1, true_pos):
    summary = simulated_summary("split_merge", preset)
    assert summary.breakpoints.f1 >= bp_f1
    assert summary.segments.true_pos >= true_pos


def noisy_wall(sigma: float, seed: int) -> Scan:
    return scan_of([((3.0, -4.0), (3.0, 4.0))], fov_deg=100, step_deg=1 / 3, sigma=sigma, seed=seed)


def test_merge_rejoins_what_noise_split():
    for seed in range(5):
        scan = noisy_wall(SIGMA, seed)
        # a 2.5 cm split threshold cuts 1 cm noise to pieces ...
        pieces = extract(scan, "split_merge", split_distance=0.025, merge_chi2=0.0)
        assert len(pieces) >= 1
        # ... which the chi-square merge puts together again
        merged = extract(scan, "split_merge", split_distance=0.025)
        assert len(merged) == 1
        assert merged.n_points[0] + merged.outliers.size == len(scan)
    cut = [len(extract(noisy_wall(SIGMA, s), "split_merge", split_distance=0.025, merge_chi2=0.0))
           for s in range(5)]  # fmt: skip
    assert max(cut) >= 3


def test_no_return_is_lost_at_a_split():
    """laser_line_extraction drops two points at every split; here none is."""
    for seed in range(3):
        scan = room_scan(seed)
        result = extract(scan, "split_merge")
        assert result.first[1:].tolist() == (result.last[:-1] + 1).tolist()
        assert int(result.n_points.sum()) == int(np.count_nonzero(scan.valid))


def test_an_isolated_return_is_an_outlier_not_two_breakpoints():
    scan = noisy_wall(SIGMA, 0)
    ranges = scan.ranges.copy()
    ranges[150] -= 1.0
    result = extract(Scan(ranges, scan.angle_min, scan.angle_increment), "split_merge")
    assert result.outliers.tolist() == [150]
    assert result.breakpoints.size == 0
    assert len(result) == 1
    assert extract(Scan(ranges, scan.angle_min, scan.angle_increment), "iepf").breakpoints.size == 2


def test_short_lines_are_not_reported():
    # a 0.3 m post 2 m ahead, in front of the door scene: shorter than min_line_length
    walls = [*door_scene(), ((2.0, -0.95), (2.0, -0.65))]
    scan = scan_of(walls, fov_deg=100, step_deg=1 / 3, sigma=SIGMA, seed=0)
    assert all(s.rho > 2.5 for s in extract(scan, "split_merge").segments)
    (post,) = [s for s in extract(scan, "split_merge", min_length=0.0).segments if s.rho < 2.5]
    assert post.rho == pytest.approx(2.0, abs=0.01)
    assert post.length == pytest.approx(0.3, abs=0.03)
