"""Metrics on hand-made detections with known scores."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scanlines import Extraction, Scan
from scanlines.evaluation.metrics import (
    accuracy_rate,
    aggregate,
    environmental_similarity,
    index_distance,
    score,
    score_events,
    score_segments,
    segment_overlap,
    wrap_angle,
)
from scanlines.evaluation.scores import (
    EventScore,
    ScanScore,
    SegmentScore,
    SimilarityScore,
    Tolerances,
)
from scanlines.sim import (
    NoiseModel,
    SensorSpec,
    Truth,
    World,
    box,
    random_scene,
    round_pillar,
    simulate,
    wall,
)

EXACT = NoiseModel()


def _extraction(
    segments: Sequence[tuple[Any, ...]] = (),  # (first, last, rho, alpha[, start, end])
    breakpoints: Sequence[int] = (),
    corners: Sequence[int] = (),
    outliers: Sequence[int] = (),
) -> Extraction:
    rows, firsts, lasts = [], [], []
    for seg in segments:
        first, last, rho, alpha = seg[:4]
        start, end = (seg[4], seg[5]) if len(seg) > 4 else ((0.0, 0.0), (0.0, 0.0))
        rows.append([rho, alpha, *start, *end, 0.0])
        firsts.append(first)
        lasts.append(last)
    m = len(rows)
    return Extraction(
        first=np.array(firsts, int),
        last=np.array(lasts, int),
        n_points=np.array([1] * m, int),
        lines=np.array(rows, float).reshape(m, 7),
        covariances=np.zeros((m, 2, 2)),
        breakpoints=np.array(breakpoints, int),
        corners=np.array(corners, int),
        outliers=np.array(outliers, int),
        method="test",
        params={},
    )


def _from_truth(truth: Truth) -> Extraction:
    s = truth.segments
    return Extraction(
        first=s.first,
        last=s.last,
        n_points=s.n_returns,
        lines=s.lines,
        covariances=np.zeros((len(s), 2, 2)),
        breakpoints=truth.breakpoints,
        corners=truth.corners,
        outliers=np.array([], int),
        method="truth",
        params={},
    )


# A 1 m box 2.5 m ahead of a wall at x = 5, lms_1deg (beam k at (k - 90) deg):
# breakpoints [78, 101]; segments wall 27..78, box 79..101, wall 102..153.
BOX_WALL = simulate(
    World([wall((5, -10), (5, 10)), box((3, 0), 1.0, 1.0)]), "lms_1deg", noise=EXACT
)


def test_box_wall_truth_is_as_the_tests_assume() -> None:
    t = BOX_WALL.truth
    assert t.breakpoints.tolist() == [78, 101]
    assert t.segments.first.tolist() == [27, 79, 102]
    assert t.segments.last.tolist() == [78, 101, 153]


# --------------------------------------------------------------------------- events


def test_event_precision_recall_f1() -> None:
    s = score_events([10, 21, 50], [11, 20, 30], tolerance=2, n_beams=180)
    assert (s.tp, s.fp, s.fn) == (2, 1, 1)
    assert s.precision == pytest.approx(2 / 3)
    assert s.recall == pytest.approx(2 / 3)
    assert s.f1 == pytest.approx(2 / 3)
    assert s.mean_offset == 1.0


def test_event_matching_is_one_to_one_and_nearest_first() -> None:
    s = score_events([10, 11], [11], tolerance=2, n_beams=180)
    assert (s.tp, s.fp, s.fn) == (1, 1, 0)
    assert s.mean_offset == 0.0  # 11 took 11, not 10
    s = score_events([12], [10, 13], tolerance=2, n_beams=180)
    assert (s.tp, s.fp, s.fn, s.offset_sum) == (1, 0, 1, 1.0)
    # a greedy chain: found 11 is nearest to true 11, so true 9 is left to found 8
    s = score_events([8, 11], [9, 11], tolerance=2, n_beams=180)
    assert (s.tp, s.offset_sum) == (2, 1.0)


def test_event_tolerance_is_a_parameter() -> None:
    assert score_events([14], [10], tolerance=2, n_beams=180).tp == 0
    assert score_events([14], [10], tolerance=4, n_beams=180).tp == 1


def test_full_circle_index_distance_wraps() -> None:
    np.testing.assert_array_equal(
        index_distance(np.array([359, 0]), np.array([1, 180]), 360, circular=True),
        [[2, 179], [1, 180]],
    )
    circ = score_events([359], [1], tolerance=2, n_beams=360, circular=True)
    line = score_events([359], [1], tolerance=2, n_beams=360, circular=False)
    assert (circ.tp, circ.fp, circ.fn, circ.offset_sum) == (1, 0, 0, 2.0)
    assert (line.tp, line.fp, line.fn) == (0, 1, 1)


def test_dont_care_true_events_are_neither_hit_nor_missed() -> None:
    hit = score_events([20], [20, 50], tolerance=2, n_beams=180, true_dont_care=[True, False])
    assert (hit.tp, hit.fp, hit.fn, hit.found_ignored, hit.true_dont_care) == (0, 0, 1, 1, 1)
    missed = score_events([], [20], tolerance=2, n_beams=180, true_dont_care=[True])
    assert (missed.tp, missed.fp, missed.fn) == (0, 0, 0)
    assert math.isnan(missed.precision)
    assert math.isnan(missed.f1)


def test_ignorable_found_events_are_not_false() -> None:
    s = score_events([5, 40], [], tolerance=2, n_beams=180, found_ignorable=[True, False])
    assert (s.fp, s.found_ignored) == (1, 1)


def test_one_beam_face_events_are_dont_care_in_score() -> None:
    # a 10 cm post 3 m ahead is hit by beam 90 alone: breakpoints 89 and 90 are don't care
    sim = simulate(World([wall((5, -10), (5, 10)), box((3, 0), 0.1, 0.1)]), "lms_1deg", noise=EXACT)
    assert sim.truth.breakpoints.tolist() == [89, 90]
    assert sim.truth.breakpoint_runs.tolist() == [[63, 1], [1, 63]]
    none = score(_extraction(), sim.truth, sim.scan)
    assert (none.breakpoints.fn, none.breakpoints.true_dont_care) == (0, 2)
    one = score(_extraction(breakpoints=[89]), sim.truth, sim.scan)
    assert (one.breakpoints.tp, one.breakpoints.fp, one.breakpoints.found_ignored) == (0, 0, 1)
    strict = score(_extraction(), sim.truth, sim.scan, Tolerances(min_run=1))
    assert strict.breakpoints.fn == 2


# --------------------------------------------------------------------------- segments


def _wall_seg(
    first: int, last: int, rho: float = 5.0, alpha: float = 0.0
) -> tuple[int, int, float, float]:
    return (first, last, rho, alpha)


def _seg_score(
    *segments: tuple[Any, ...], truth: Truth | None = None, tol: Tolerances | None = None
) -> SegmentScore:
    return score_segments(_extraction(segments), truth or BOX_WALL.truth, tol or Tolerances())


def test_perfect_segments() -> None:
    s = score_segments(_from_truth(BOX_WALL.truth), BOX_WALL.truth, Tolerances())
    assert (s.n_true, s.n_found, s.matched, s.false, s.split, s.merge) == (3, 3, 3, 0, 0, 0)
    assert (s.true_pos, s.false_pos) == (1.0, 0.0)
    assert s.mean_abs_drho == 0.0
    assert s.mean_endpoint_error == 0.0


@pytest.mark.parametrize(("rho", "matched"), [(5.04, 1), (4.96, 1), (5.06, 0), (4.94, 0)])
def test_rho_tolerance(rho: float, matched: int) -> None:
    s = _seg_score(_wall_seg(27, 78, rho=rho))
    assert s.matched == matched
    assert s.false == 1 - matched
    assert s.true_pos == pytest.approx(matched / 3)
    if matched:
        assert s.mean_abs_drho == pytest.approx(0.04)


@pytest.mark.parametrize(("deg", "matched"), [(3.9, 1), (-3.9, 1), (4.1, 0), (-4.1, 0)])
def test_alpha_tolerance(deg: float, matched: int) -> None:
    s = _seg_score(_wall_seg(27, 78, alpha=math.radians(deg)))
    assert s.matched == matched
    if matched:
        assert math.degrees(s.mean_abs_dalpha) == pytest.approx(3.9)


def test_overlap_must_cover_half_of_both_segments() -> None:
    assert _seg_score(_wall_seg(27, 60)).matched == 1  # 34 of 52 true beams
    assert _seg_score(_wall_seg(27, 50)).matched == 0  # 24 of 52
    # found 10..78 (69 beams) shares 52 with the truth: 75 % of the found, 100 % of the true
    assert _seg_score(_wall_seg(10, 78)).matched == 1
    # found 0..120 shares 52 beams with the truth: under half of its own 121
    assert _seg_score(_wall_seg(0, 120)).matched == 0


def test_split_error() -> None:
    s = _seg_score(_wall_seg(27, 50), _wall_seg(51, 78))
    assert s.split == 1
    assert s.merge == 0
    # 51..78 still covers 28 of 52 beams: matched; 27..50 matches nothing
    assert (s.matched, s.false) == (1, 1)
    assert s.false_pos == 0.5


def test_merge_error() -> None:
    s = _seg_score(_wall_seg(27, 101), _wall_seg(102, 153))
    assert s.merge == 1
    assert s.split == 0
    # 27..101 has the wall's line and covers the first wall piece: it matches that one
    assert (s.matched, s.false, s.true_pos) == (2, 0, pytest.approx(2 / 3))


def test_endpoint_error_and_line_errors_are_means_over_matches() -> None:
    t = BOX_WALL.truth.segments
    start = t.start[0] + (0.0, 0.03)
    end = t.end[0] + (0.05, 0.0)
    box_seg = (79, 101, 2.52, math.radians(1.0), t.start[1], t.end[1])
    s = _seg_score((27, 78, 5.0, 0.0, start, end), box_seg)
    assert s.matched == 2
    assert s.mean_endpoint_error == pytest.approx((0.04 + 0.0) / 2)
    assert s.mean_abs_drho == pytest.approx(0.01)
    assert math.degrees(s.mean_abs_dalpha) == pytest.approx(0.5)


def test_short_segments_are_dont_care_both_ways() -> None:
    # a 0.36 m box 3 m ahead is hit by 7 beams (87..93): a don't-care true segment
    sim = simulate(
        World([wall((5, -10), (5, 10)), box((3, 0), 0.36, 0.36)]), "lms_1deg", noise=EXACT
    )
    truth = sim.truth
    assert list(zip(truth.segments.first, truth.segments.last, strict=True)) == [
        (27, 86),
        (87, 93),
        (94, 153),
    ]
    box_rho = truth.segments.rho[1]
    # the box missed: not counted; a 5-beam garbage segment: not false
    s = _seg_score(_wall_seg(27, 86), _wall_seg(94, 153), _wall_seg(40, 44, rho=9.0), truth=truth)
    assert (s.n_true, s.matched, s.true_pos) == (2, 2, 1.0)
    assert (s.n_found, s.found_dont_care, s.false) == (2, 1, 0)
    # an 8-beam found segment on the 7-beam box is neither right nor wrong
    s = _seg_score(_wall_seg(87, 94, rho=box_rho), truth=truth)
    assert (s.found_ignored, s.false, s.false_pos) == (1, 0, pytest.approx(math.nan, nan_ok=True))
    # with the threshold at 1 beam the box counts
    s = _seg_score(_wall_seg(87, 93, rho=box_rho), truth=truth, tol=Tolerances(min_segment_beams=1))
    assert (s.n_true, s.matched) == (3, 1)


def test_segments_on_round_pillars_are_not_false_unless_asked() -> None:
    world = World([wall((5, -10), (5, 10)), round_pillar((3, 0), 0.5, sides=40)])
    sim = simulate(world, "lms_1deg", noise=EXACT)
    pillar = np.flatnonzero(sim.truth.on_curve)
    found = (int(pillar[0]), int(pillar[-1]), 2.6, 0.0)
    assert found[1] - found[0] + 1 >= 8
    assert _seg_score(found, truth=sim.truth).false == 0
    strict = Tolerances(curved_dont_care=False)
    assert _seg_score(found, truth=sim.truth, tol=strict).false == 1


def test_alpha_matching_wraps_around_pi() -> None:
    # full-circle sensor; the wall x = -2 has alpha = pi in the sensor frame
    ring = SensorSpec("ring", 360, math.radians(-179.5), math.radians(1.0), 0.0, 30.0)
    sim = simulate(World([wall((-2, -3), (-2, 3))]), ring, noise=EXACT)
    t = sim.truth.segments
    assert len(t) == 1
    assert t.first[0] > t.last[0]  # the wall straddles the seam behind the sensor
    np.testing.assert_allclose([t.rho[0], abs(t.alpha[0])], [2.0, math.pi])
    s = _seg_score((int(t.first[0]), int(t.last[0]), 2.0, -math.pi + 0.01), truth=sim.truth)
    assert s.matched == 1
    assert s.mean_abs_dalpha == pytest.approx(0.01)
    np.testing.assert_allclose(
        wrap_angle(np.array([3 * math.pi / 2, -math.pi, 0.1])), [-math.pi / 2, math.pi, 0.1]
    )


def test_segment_overlap_across_the_seam() -> None:
    shared = segment_overlap(
        np.array([350, 10]), np.array([9, 20]), np.array([355, 0]), np.array([20, 5]), 360
    )
    # 350..9 vs 355..20: 355..359 and 0..9; 350..9 vs 0..5: 6; 10..20 vs 355..20: 11
    np.testing.assert_array_equal(shared, [[15, 6], [11, 0]])


# --------------------------------------------------------------------------- paper measures


def test_environmental_similarity_uses_valid_non_outlier_points() -> None:
    angles = np.radians(np.arange(-30.0, 31.0))
    x = np.where(np.arange(61) % 2 == 0, 2.01, 2.03)  # points 1 and 3 cm behind x = 2
    ranges = x / np.cos(angles)
    ranges[10] = np.inf  # no return: not a point
    ranges[20] = 0.7  # an outlier the extractor rejected
    scan = Scan(ranges, angle_min=angles[0], angle_increment=math.radians(1.0))
    ext = _extraction([(0, 60, 2.0, 0.0)], outliers=[20])
    sim = environmental_similarity(ext, scan)
    assert sim.n_points == 59
    d = np.abs(np.delete(x, [10, 20]) - 2.0)
    assert sim.mean == pytest.approx(d.mean())
    assert sim.rms == pytest.approx(math.sqrt((d**2).mean()))
    assert sim.max_distance == pytest.approx(0.03)


def test_environmental_similarity_across_the_seam() -> None:
    scan = Scan(np.full(360, 2.0), angle_min=0.0, angle_increment=math.radians(1.0))
    ext = _extraction([(350, 9, 1.9, 0.0)])
    sim = environmental_similarity(ext, scan)
    assert sim.n_points == 20
    expected = np.abs(2.0 * np.cos(np.radians(np.r_[350:360, 0:10])) - 1.9)
    assert sim.mean == pytest.approx(expected.mean())


def test_accuracy_rate_is_the_papers_count_formula() -> None:
    assert accuracy_rate(5, 4, 2, 4) == pytest.approx(0.625)
    assert accuracy_rate(4, 4, 4, 4) == 1.0
    assert accuracy_rate(20, 4, 0, 4) == pytest.approx(-1.5)
    assert math.isnan(accuracy_rate(1, 0, 0, 0))


# --------------------------------------------------------------------------- per scan, pooled


def test_score_of_the_truth_itself_is_perfect_on_noisy_random_scenes() -> None:
    for seed, sensor in enumerate(("lms_1deg", "tim571", "urg04lx")):
        sim = random_scene(seed, sensor).scan(seed)
        s = score(_from_truth(sim.truth), sim.truth, sim.scan)
        for events in (s.breakpoints, s.corners):
            assert (events.fp, events.fn) == (0, 0)
            assert events.tp == events.n_true - events.true_dont_care
        assert s.breakpoints.f1 == 1.0
        assert (s.segments.true_pos, s.segments.false_pos) == (1.0, 0.0)
        assert s.accuracy_rate == 1.0


def test_score_result_carries_tolerances_and_serialises() -> None:
    tol = Tolerances(event_beams=3, rho=0.1)
    s = score(_from_truth(BOX_WALL.truth), BOX_WALL.truth, BOX_WALL.scan, tol)
    assert s.tolerances is tol
    row = s.to_dict()
    assert row["tol_event_beams"] == 3
    assert row["tol_rho"] == 0.1
    assert row["bp_tp"] == 2
    assert row["seg_matched"] == 3
    assert json.loads(json.dumps(row))["accuracy_rate"] == 1.0


def test_score_checks_the_beam_count() -> None:
    short = Scan(np.ones(10), angle_min=0.0, angle_increment=0.01)
    with pytest.raises(ValueError, match="beams"):
        score(_extraction(), BOX_WALL.truth, short)
    with pytest.raises(ValueError, match="breakpoints"):
        score(_extraction(breakpoints=[500]), BOX_WALL.truth, BOX_WALL.scan)


def _scan_score(bp: EventScore, corners: EventScore, tol: Tolerances | None = None) -> ScanScore:
    return ScanScore(
        breakpoints=bp,
        corners=corners,
        segments=SegmentScore(n_true=2, matched=1, sum_abs_drho=0.02),
        similarity=SimilarityScore(n_points=2, sum_distance=0.02, sum_sq_distance=0.0002),
        accuracy_rate=accuracy_rate(bp.n_found, bp.n_true, corners.n_found, corners.n_true),
        tolerances=tol or Tolerances(),
    )


def test_aggregate_micro_averages_counts() -> None:
    a = _scan_score(EventScore(tp=1, n_true=4, n_found=5), EventScore(n_true=4, n_found=2))
    b = _scan_score(EventScore(tp=1, fp=2, fn=1, n_true=2, n_found=2), EventScore())
    summary = aggregate([a, b])
    assert summary.n_scans == 2
    assert summary.breakpoints.precision == 0.5  # 2 / 4, not the mean of 1 and 1/3
    assert summary.breakpoints.recall == pytest.approx(2 / 3)
    assert summary.segments.true_pos == 0.5
    assert summary.segments.mean_abs_drho == pytest.approx(0.02)
    assert summary.similarity.mean == pytest.approx(0.01)
    # accuracy: a = 0.625, b = 1.0; pooled 1 - (1 + 2 + 0 + 0) / (4 + 4 + 2 + 0)
    assert summary.accuracy_rate_mean == pytest.approx(0.8125)
    assert summary.accuracy_rate_pooled == pytest.approx(0.7)
    row = summary.to_dict()
    assert row["n_scans"] == 2
    assert row["bp_precision"] == 0.5
    assert "tol_alpha" in row


def test_aggregate_refuses_mixed_tolerances_and_nothing() -> None:
    a = _scan_score(EventScore(), EventScore())
    b = replace(a, tolerances=Tolerances(event_beams=5))
    with pytest.raises(ValueError, match="tolerances"):
        aggregate([a, b])
    with pytest.raises(ValueError, match="at least one"):
        aggregate([])


@settings(max_examples=80, deadline=None)
@given(
    found=st.lists(st.integers(0, 99), max_size=12, unique=True),
    true=st.lists(st.integers(0, 99), max_size=12, unique=True),
    dont_care=st.lists(st.booleans(), min_size=12, max_size=12),
    tolerance=st.integers(0, 3),
    circular=st.booleans(),
)
def test_event_counts_always_add_up(
    found: list[int], true: list[int], dont_care: list[bool], tolerance: int, circular: bool
) -> None:
    dc = np.array(dont_care[: len(true)], bool)
    s = score_events(
        found, true, tolerance=tolerance, n_beams=100, circular=circular, true_dont_care=dc
    )
    assert s.tp + s.fp + s.found_ignored == len(found)
    assert s.tp + s.fn + s.true_dont_care == len(true)
    assert s.offset_sum <= s.tp * tolerance
    # nothing within tolerance of any true event can be a true positive
    if len(found) and len(true):
        near = index_distance(np.array(found), np.array(true), 100, circular=circular)
        assert s.tp <= np.count_nonzero((near <= tolerance).any(axis=0) & ~dc)
    else:
        assert s.tp == 0
