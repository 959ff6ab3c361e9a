"""The surfaces method (the default): dense and wavy walls whole, pieces of one wall on one
line, no events inside a wall, and the noise an extractor learns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines import Extractor, Scan, extract
from scanlines.data import sample
from scanlines.extractor import at_float32, float32
from scanlines.io import open_log
from scanlines.sensor import learned_noise
from scanlines.sensor.profile import estimate_profile


def _wall_ranges(bearings, distance, normal, waviness=0.0, period=0.5):
    """Ranges of a wall ``distance`` from the sensor, its normal at ``normal`` rad, bent
    across by ``waviness`` m (a sine of ``period`` m along it)."""
    ranges = distance / np.cos(bearings - normal)
    along = ranges * np.sin(bearings - normal)
    bend = waviness * np.sin(2.0 * math.pi * along / period)
    return (distance + bend) / np.cos(bearings - normal)


@pytest.mark.parametrize("increment_deg", [0.1, 0.25, 0.5])
@pytest.mark.parametrize("seed", range(3))
def test_a_wall_with_millimetres_of_smooth_waviness_comes_out_whole(increment_deg, seed):
    bearings = np.radians(np.arange(-50.0, 50.0, increment_deg))
    ranges = _wall_ranges(bearings, 3.0, 0.2, waviness=0.003)
    ranges += np.random.default_rng(seed).normal(0.0, 0.005, ranges.shape)
    scan = Scan(ranges, bearings[0], math.radians(increment_deg), range_max=30.0)
    result = extract(scan, "surfaces")
    assert len(result) == 1
    assert result.n_points[0] >= 0.95 * np.count_nonzero(scan.valid)


def test_a_wall_seen_in_two_pieces_behind_a_post_gets_one_line():
    bearings = np.radians(np.arange(-45.0, 45.0, 0.5))
    ranges = _wall_ranges(bearings, 4.0, 0.1)
    post = np.abs(bearings) < math.radians(4.0)
    ranges[post] = 1.5 / np.cos(bearings[post])
    ranges += np.random.default_rng(1).normal(0.0, 0.01, ranges.shape)
    scan = Scan(ranges, bearings[0], math.radians(0.5), range_max=30.0)
    result = extract(scan, "surfaces")
    wall = result.lines[:, 0] > 3.0
    assert np.count_nonzero(wall) == 2
    (left, right) = result.lines[wall]
    assert left[0] == right[0]  # one estimate, reported twice
    assert left[1] == right[1]
    assert left[0] == pytest.approx(4.0, abs=0.005)
    assert left[1] == pytest.approx(0.1, abs=0.002)
    own = extract(Scan(np.where(bearings < 0, ranges, np.nan), bearings[0], math.radians(0.5),
                       range_max=30.0), "surfaces")  # fmt: skip
    pooled_sigma = result.covariances[wall][0, 0, 0]
    assert pooled_sigma < own.covariances[0, 0, 0]  # the pooled line is better determined


def test_a_spike_left_out_of_a_wall_is_no_breakpoint():
    bearings = np.radians(np.arange(-40.0, 40.0, 0.5))
    ranges = _wall_ranges(bearings, 3.0, 0.0)
    ranges += np.random.default_rng(2).normal(0.0, 0.005, ranges.shape)
    ranges[80] = 1.2
    scan = Scan(ranges, bearings[0], math.radians(0.5), range_max=30.0)
    result = extract(scan, "surfaces")
    assert len(result) == 1
    assert result.breakpoints.size == 0
    assert 80 in result.outliers.tolist()
    assert extract(scan, "partition").breakpoints.size > 0  # the partition's events do report it


@pytest.mark.parametrize("beams", [100_000, 300_000])
def test_a_densely_sampled_square_room_is_four_walls(beams):
    """The reliability issue's room: 5 m from the sensor, 1 cm range noise, one full turn."""
    step = 2.0 * math.pi / beams
    bearings = -math.pi + step * np.arange(beams)
    facing = np.round(bearings / (math.pi / 2)) * (math.pi / 2)
    ranges = 5.0 / np.cos(bearings - facing)
    ranges += np.random.default_rng(3).normal(0.0, 0.01, beams)
    scan = Scan(ranges, -math.pi, step, range_max=30.0)
    result = extract(scan, "surfaces")
    assert len(result) == 4
    assert result.n_points.sum() >= 0.99 * beams


def test_an_extractor_without_a_profile_learns_the_noise_run_measures(monkeypatch):
    monkeypatch.setattr(learned_noise, "LEARNED_SCANS", 20)
    scans = list(open_log(sample("intel")))[:30]
    # The learner measures the ranges the kernels take, at float32 precision.
    taken = [
        Scan(at_float32(s.ranges), s.angle_min, s.angle_increment, s.range_min, s.range_max)
        for s in scans[:20]
    ]
    profile = estimate_profile(taken, max_scans=20)
    learning, profiled = Extractor("surfaces"), Extractor("surfaces", sensor_profile=profile)
    own = Extractor("surfaces", noise_sigma=0.01)  # differs from both: the check can fail
    for k, scan in enumerate(scans):
        extraction = learning(scan)
        if k >= 20:
            assert extraction.lines.tolist() == profiled(scan).lines.tolist()
    first = scans[0]
    geometry = (len(first), float32(first.angle_min), float32(first.angle_increment))
    assert learning._learner.line(geometry) == profile.noise
    assert own(scans[-1]).lines.tolist() != profiled(scans[-1]).lines.tolist()


def test_batch_learns_as_the_scans_one_by_one_do(monkeypatch):
    monkeypatch.setattr(learned_noise, "LEARNED_SCANS", 5)
    scans = list(open_log(sample("intel")))[:12]
    extractor = Extractor("surfaces")
    one_by_one = [extractor(scan) for scan in scans]
    first = scans[0]
    stack = np.stack([scan.ranges for scan in scans])
    sensor = (first.angle_min, first.angle_increment, first.range_min, first.range_max)
    table = Extractor("surfaces").batch(stack, *sensor, jobs=2)
    for k, extraction in enumerate(one_by_one):
        assert table[k].lines.tolist() == extraction.lines.tolist()
        assert table[k].breakpoints.tolist() == extraction.breakpoints.tolist()


def _noisy_intel_scans(count: int) -> list[Scan]:
    """Shipped scans with float64 noise added: ranges no float32 holds exactly."""
    rng = np.random.default_rng(5)
    return [
        Scan(s.ranges + rng.normal(0.0, 1e-4, len(s)), s.angle_min, s.angle_increment, 0.0, 50.0)
        for s in list(open_log(sample("intel")))[:count]
    ]


def test_batch_equals_the_calls_to_the_bit_while_learning():
    scans = _noisy_intel_scans(40)
    calls = Extractor("surfaces")
    one_by_one = [calls(scan) for scan in scans]
    stack = np.stack([scan.ranges for scan in scans])
    table = Extractor("surfaces").batch(
        stack, scans[0].angle_min, scans[0].angle_increment, 0.0, 50.0
    )
    for k, extraction in enumerate(one_by_one):
        assert table[k].lines.tobytes() == extraction.lines.tobytes()
        assert table[k].covariances.tobytes() == extraction.covariances.tobytes()
        assert table[k].breakpoints.tolist() == extraction.breakpoints.tolist()


def _lines_in_order(extractor: Extractor, scans: list[Scan]) -> list[bytes]:
    return [extractor(scan).lines.tobytes() for scan in scans]


def test_threads_sharing_a_bare_extractor_each_learn_from_their_own_scans():
    import threading

    scans = _noisy_intel_scans(48)
    shares = [scans[k::8] for k in range(8)]  # each thread's scans, in its order
    expected = [_lines_in_order(Extractor("surfaces"), share) for share in shares]
    shared = Extractor("surfaces")
    got: list[list[bytes]] = [[] for _ in shares]
    start = threading.Barrier(len(shares))

    def work(k: int) -> None:
        start.wait()
        got[k] = _lines_in_order(shared, shares[k])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(shares))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert got == expected
    # the learning shows: each scan alone (its own noise estimate) gives other lines
    alone = [Extractor("surfaces")(scan).lines.tobytes() for scan in shares[0]]
    assert alone != expected[0]


def _same_partition(a, b) -> bool:
    return all(
        np.array_equal(getattr(a, name), getattr(b, name)) for name in ("first", "last", "outliers")
    )


@pytest.mark.parametrize("log", ["intel", "freiburg", "urg"])
def test_the_two_stage_search_finds_the_full_searchs_partition_on_the_shipped_scans(log):
    scans = list(open_log(sample(log)))
    full, two_stage = Extractor("surfaces"), Extractor("surfaces", two_stage=True)
    same = sum(_same_partition(full(scan), two_stage(scan)) for scan in scans)
    assert same >= 0.99 * len(scans)  # 299, 299 and 150 of 300, 300 and 150 on 2026-12-07


def test_the_two_stage_search_keeps_a_dense_room_four_walls():
    beams = 20_000
    step = 2.0 * math.pi / beams
    bearings = -math.pi + step * np.arange(beams)
    facing = np.round(bearings / (math.pi / 2)) * (math.pi / 2)
    ranges = 5.0 / np.cos(bearings - facing)
    ranges += np.random.default_rng(3).normal(0.0, 0.01, beams)
    scan = Scan(ranges, -math.pi, step, range_max=30.0)
    result = extract(scan, "surfaces", two_stage=True)
    assert len(result) == 4
    assert result.corners.size == 4
