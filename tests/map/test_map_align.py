"""Scan-to-map alignment (scanlines.map.align): a simulated log with known pose noise mapped
with and without it, and the fallback to the log's pose where a scene pins no direction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines import Scan
from scanlines.map import build_map
from scanlines.map.align import AlignSettings, LineSet, align_points, align_scan
from scanlines.map.holdout import score_held_out
from test_map import view

ROOM = [((-4.0, -3.0), (4.0, -3.0)), ((4.0, -3.0), (4.0, 3.0)), ((4.0, 3.0), (-4.0, 3.0)),
        ((-4.0, 3.0), (-4.0, -3.0)), ((1.0, -3.0), (1.0, -1.0))]  # fmt: skip


def room_lines(walls) -> LineSet:
    start = np.array([a for a, _ in walls], dtype=float)
    end = np.array([b for _, b in walls], dtype=float)
    d = end - start
    alpha = np.arctan2(d[:, 0], -d[:, 1])
    rho = np.sum(start * np.column_stack((np.cos(alpha), np.sin(alpha))), axis=1)
    alpha = np.where(rho < 0, alpha + math.pi, alpha)
    return LineSet(np.abs(rho), alpha, start, end)


def noisy_log(n: int = 60, xy: float = 0.015, theta: float = math.radians(0.4)):
    """Scans of ROOM along a path, each carrying its true pose plus known noise."""
    rng = np.random.default_rng(7)
    scans = []
    for k in range(n):
        true = (-2.0 + 4.0 * k / n, 0.5 * math.sin(k / 9), 0.3 * math.sin(k / 13))
        scan = view(ROOM, true, seed=k, sigma=0.003)
        noise = (rng.normal(0, xy), rng.normal(0, xy), rng.normal(0, theta))
        pose = tuple(t + e for t, e in zip(true, noise, strict=True))
        scans.append(Scan(scan.ranges, scan.angle_min, scan.angle_increment, pose=pose))
    return scans


def test_a_scan_moved_off_its_pose_is_pulled_back_onto_the_map():
    true = (0.5, 0.2, 0.1)
    scan = view(ROOM, true, seed=3, sigma=0.003)
    fit = align_scan(scan, (0.54, 0.17, 0.1 + math.radians(1.0)), room_lines(ROOM), AlignSettings())
    assert fit.used
    assert fit.pose[0] == pytest.approx(true[0], abs=0.005)
    assert fit.pose[1] == pytest.approx(true[1], abs=0.005)
    assert fit.pose[2] == pytest.approx(true[2], abs=math.radians(0.1))


def test_one_wall_pins_no_shift_along_it_so_the_log_pose_stands():
    wall = [((-5.0, 2.0), (5.0, 2.0))]
    scan = view(wall, (0.0, 0.0, 0.0), seed=1, sigma=0.003)
    given = (0.05, 0.01, 0.0)
    fit = align_scan(scan, given, room_lines(wall), AlignSettings())
    assert not fit.used
    assert fit.pose == given


def test_a_correction_beyond_the_bound_is_refused():
    scan = view(ROOM, (0.0, 0.0, 0.0), seed=2, sigma=0.003)
    given = (0.08, 0.0, 0.0)
    fit = align_points(
        scan.points[scan.valid], given, room_lines(ROOM), max_shift=0.03,
        max_turn=math.radians(2.0), gate=0.15, least=0.02,
    )  # fmt: skip
    assert not fit.used
    assert fit.pose == given


def _score(scans, align):
    build = build_map(enumerate(scans), hold_out=lambda k: k % 10 == 0, align=align)
    return score_held_out(enumerate(scans), build, lambda r: np.full(len(r), 0.003)), build


def test_alignment_tightens_a_map_of_a_log_with_pose_noise():
    scans = noisy_log()
    raw, _ = _score(scans, None)
    aligned, build = _score(scans, AlignSettings())
    assert build.aligned > 0.8 * build.scans
    assert math.isnan(raw.localised_median_distance)
    assert aligned.localised_median_distance < 0.7 * raw.median_distance
    assert aligned.localised_coverage >= raw.coverage
    assert aligned.segments_per_line >= raw.segments_per_line


def test_a_damped_alignment_moves_the_pose_part_of_the_way():
    scan = view(ROOM, (0.5, 0.2, 0.1), seed=4, sigma=0.003)
    given = (0.54, 0.2, 0.1)
    full = align_scan(scan, given, room_lines(ROOM), AlignSettings())
    half = align_scan(scan, given, room_lines(ROOM), AlignSettings(damping=0.5))
    assert full.used
    assert half.used
    assert half.pose[0] == pytest.approx((given[0] + full.pose[0]) / 2, abs=1e-9)
    assert abs(half.pose[0] - 0.5) > 0.015
