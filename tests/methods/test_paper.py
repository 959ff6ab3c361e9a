"""The ``paper`` method: the adaptive method's paper preset bit for bit, and the paper's
steps on hand-built scans."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scanlines import Extraction, Extractor, Scan, method_info
from scanlines.sensor.profile import estimate_profile
from scenes import beam_of, scan_of
from test_properties import check_order, scans
from tools.benchmarks import same_features

# The paper's parameters changed one at a time, and all at once.
OVERRIDES = (
    {},
    {"k": 5.0},
    {"window": 5},
    {"dkth_range": (0.0, 0.05)},
    {"min_points": 4},
    {"range_sigma": 0.01},
    {"k": 5.0, "window": 5, "dkth_range": (0.0, 0.05), "min_points": 4, "range_sigma": 0.01},
)
IDS = [",".join(f"{k}={v}" for k, v in o.items()) or "defaults" for o in OVERRIDES]


def assert_identical(paper: Extraction, adaptive: Extraction, where: str) -> None:
    for field in same_features.FIELDS:
        a, b = np.asarray(getattr(paper, field)), np.asarray(getattr(adaptive, field))
        assert a.dtype == b.dtype, (where, field)
        assert a.shape == b.shape, (where, field)
        assert np.array_equal(a, b, equal_nan=True), (where, field)


@pytest.fixture(scope="module")
def scan_sets():
    """The record's simulated scans and every scan of the three shipped excerpts."""
    return same_features.scans(8, None)


def test_parameters_are_the_papers():
    info = method_info("paper")
    assert set(info.params) == {
        "window", "k", "dkth_range", "dkth_step", "max_evaluations",
        "min_points", "min_length", "range_sigma",
    }  # fmt: skip
    defaults = {name: p.default for name, p in info.params.items()}
    adaptive = method_info("adaptive")
    preset = adaptive.presets["paper"]
    for name, value in defaults.items():
        assert value == preset.get(name, adaptive.params[name].default), name
    assert info.presets == {}


@pytest.mark.parametrize("overrides", OVERRIDES, ids=IDS)
def test_every_shipped_scan_gives_the_adaptive_paper_preset_bit_for_bit(scan_sets, overrides):
    paper = Extractor("paper", **overrides)
    adaptive = Extractor("adaptive", preset="paper", **overrides)
    count = 0
    for items in scan_sets.values():
        for label, scan in items:
            assert_identical(paper(scan), adaptive(scan), label)
            count += 1
    assert count == 43 + 300 + 300 + 150  # simulated and synthetic, Intel, Freiburg, URG


@pytest.mark.parametrize("excerpt", same_features.EXCERPTS)
def test_batches_and_sensor_profiles_give_the_adaptive_paper_preset(scan_sets, excerpt):
    items = scan_sets[excerpt]
    profile = estimate_profile([scan for _, scan in items], source=excerpt)
    paper = Extractor("paper", sensor_profile=profile)
    adaptive = Extractor("adaptive", preset="paper", sensor_profile=profile)
    for label, scan in items:
        assert_identical(paper(scan), adaptive(scan), label)
    first = items[0][1]
    stack = np.stack([scan.ranges for _, scan in items])
    batches = [
        Extractor(method, preset).batch(
            stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
        )
        for method, preset in (("paper", None), ("adaptive", "paper"))
    ]
    assert len(batches[0]) == len(items)
    for k, (a, b) in enumerate(zip(*batches, strict=True)):
        assert_identical(a, b, f"{excerpt}:{k} (batch)")


overrides_drawn = st.fixed_dictionaries(
    {},
    optional={
        "k": st.floats(0.5, 10.0),
        "window": st.integers(1, 30),
        "dkth_range": st.tuples(st.floats(0.0, 0.1), st.floats(0.0, 1.0)).map(
            lambda t: (t[0], t[0] + t[1] + 1e-3)
        ),
        "dkth_step": st.floats(1e-3, 0.1),
        "max_evaluations": st.integers(1, 200),
        "min_points": st.integers(2, 8),
        "min_length": st.floats(0.0, 1.0),
        "range_sigma": st.sampled_from(["auto", 0.01, 0.05]),
    },
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scan=scans(), overrides=overrides_drawn)
def test_any_scan_gives_the_adaptive_paper_preset_bit_for_bit(scan, overrides):
    paper = Extractor("paper", **overrides)(scan)
    adaptive = Extractor("adaptive", preset="paper", **overrides)(scan)
    assert_identical(paper, adaptive, "drawn scan")
    check_order(paper, len(scan), scan.full_circle)


# --------------------------------------------------------------------------- the paper's steps


def diamond_room() -> list:
    """A square room turned by 45 deg: corners 2 m ahead, left, behind and right, so that no
    wall is parallel to the y axis (y = kx + b describes every one)."""
    c = [(2.0, 0.0), (0.0, 2.0), (-2.0, 0.0), (0.0, -2.0)]
    return [(c[i], c[(i + 1) % 4]) for i in range(4)]


def test_a_room_gives_its_walls_with_finite_lines_and_its_corners():
    """Noise-free, 1 deg: each wall is one long segment on its line (rho sqrt(2) m, alpha
    +-45 or +-135 deg); |Dk| peaks on both sides of a corner, so the smallest SSE also keeps
    a short piece across it, and every corner is reported within 3 beams."""
    scan = scan_of(diamond_room(), fov_deg=340, step_deg=1.0, start_deg=-170)
    result = Extractor("paper")(scan)
    assert np.isfinite(result.lines).all()
    assert len(result.breakpoints) == 0
    walls = [s for s in result.segments if s.n_points >= 70]  # in beam order
    assert len(walls) == 4
    for segment, alpha in zip(walls, (-135.0, -45.0, 45.0, 135.0), strict=True):
        assert segment.rho == pytest.approx(math.sqrt(2.0), abs=1e-3)
        assert math.degrees(segment.alpha) == pytest.approx(alpha, abs=0.1)
    for bearing in (-90.0, 0.0, 90.0):
        corner = beam_of(scan, math.radians(bearing))
        assert np.abs(result.corners - corner).min() <= 3, bearing
    assert all(s.n_points <= 6 for s in result.segments if s.n_points < 70)


def wall_with_a_spike(depth: float) -> tuple[Scan, int]:
    """A noise-free wall at y = 3 m seen from 45 to 135 deg at 1/3 deg, the beam at 80 deg
    ``depth`` m short."""
    scan = scan_of([((-10.0, 3.0), (10.0, 3.0))], fov_deg=90, step_deg=1 / 3, start_deg=45)
    spike = beam_of(scan, math.radians(80.0))
    ranges = scan.ranges.copy()
    ranges[spike] -= depth
    return Scan(ranges, scan.angle_min, scan.angle_increment), spike


def test_the_window_mean_moves_a_spike_and_its_neighbours_to_one_point():
    """Steps 2-3: the 2 cm spike is a noise point; it and its two neighbours become the
    mean of 10 points, one point: their 3-point run has no y = kx + b line (NaN), and the
    pieces on either side stay on the wall. With a window of one point the three move to
    the spike instead, and the piece after it turns away from the wall."""
    scan, spike = wall_with_a_spike(0.02)
    result = Extractor("paper")(scan)
    assert len(result.breakpoints) == 0
    segments = list(result.segments)
    (k,) = [k for k, s in enumerate(segments) if s.first == spike - 1]
    triple = segments[k]
    assert (triple.last, triple.n_points) == (spike + 1, 3)
    assert math.isnan(triple.rho)
    assert math.isnan(triple.alpha)
    for side in (segments[k - 1], segments[k + 1]):
        assert side.rho == pytest.approx(3.0, abs=0.015)
        assert math.degrees(side.alpha) == pytest.approx(90.0, abs=2.0)
    assert sum(math.isnan(s.rho) for s in result.segments) == 1
    unsmoothed = Extractor("paper", window=1)(scan)
    (after,) = [s for s in unsmoothed.segments if s.first == spike + 1]
    assert abs(math.degrees(after.alpha) - 90.0) > 10.0
