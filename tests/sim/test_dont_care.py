"""Events the noise hides are don't care: stated in the truth, honoured by the scores."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines import Extraction
from scanlines.evaluation.metrics import score
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.truth_row import truth_extraction
from scanlines.sim import NoiseModel, SensorSpec, World, polyline, simulate, wall
from scanlines.sim.truth import HIDDEN_K

SIGMA = 0.01
# 0.5 deg beams over the front, Gaussian noise only (no dropouts, outliers or quantum)
SENSOR = SensorSpec(
    "test", 361, math.radians(-90), math.radians(0.5), 0.0, 30.0, NoiseModel(sigma=SIGMA)
)


def _step_scene(step: float) -> World:
    """A wall 2 m ahead below the x axis, and one ``step`` behind it above."""
    return World([wall((2, -2), (2, 0)), wall((2 + step, 0), (2 + step, 2))])


@pytest.mark.parametrize(("sigmas", "hidden"), [(2.0, True), (5.0, False)])
def test_a_depth_step_under_three_combined_sigmas_is_dont_care(sigmas, hidden) -> None:
    assert HIDDEN_K * math.sqrt(2) == pytest.approx(4.243, abs=1e-3)  # 2 < 4.24 < 5
    truth = simulate(_step_scene(sigmas * SIGMA), SENSOR, seed=1).truth
    assert len(truth.breakpoints) == 1
    assert truth.breakpoint_dont_care.tolist() == [hidden]
    assert truth.dont_care_breakpoints.tolist() == (truth.breakpoints.tolist() if hidden else [])
    # without noise nothing is hidden: the same step is a plain breakpoint
    exact = simulate(_step_scene(sigmas * SIGMA), SENSOR, noise=NoiseModel()).truth
    assert exact.breakpoint_dont_care.tolist() == [False]


def _corner_scene(turn_deg: float, side: float = 0.3) -> World:
    """Two ``side`` long walls meeting 2 m ahead, the second turned by ``turn_deg``."""
    vertex = np.array([2.0, 0.0])
    first = np.radians(80.0)  # the first side runs at 80 deg (nearly across the view)
    second = first + np.radians(turn_deg)
    a = vertex - side * np.array([math.cos(first), math.sin(first)])
    b = vertex + side * np.array([math.cos(second), math.sin(second)])
    return World([polyline([a, vertex, b])])


@pytest.mark.parametrize(("turn", "hidden"), [(2.0, True), (90.0, False)])
def test_a_turn_under_what_the_sides_resolve_is_dont_care(turn, hidden) -> None:
    noise = NoiseModel(sigma=0.03)
    truth = simulate(_corner_scene(turn), SENSOR, noise=noise, seed=2).truth
    assert len(truth.corners) == 1
    assert truth.corner_runs.min() >= 3  # not don't care for being next to a short run
    assert truth.corner_dont_care.tolist() == [hidden]
    # the resolvable angle, 3 sqrt(s1^2 + s2^2) with s = sigma sqrt(12 / n) / L roughly
    n = truth.corner_runs[0]
    rough = HIDDEN_K * math.sqrt(2) * 0.03 * math.sqrt(12 / n.mean()) / 0.3
    assert math.radians(2.0) < rough < math.radians(90.0)


def test_a_two_degree_turn_is_resolved_with_little_noise_and_long_sides() -> None:
    truth = simulate(_corner_scene(2.0, side=1.5), SENSOR, noise=NoiseModel(sigma=0.001)).truth
    assert truth.corner_dont_care.tolist() == [False]


def test_a_detection_at_a_dont_care_event_is_neither_true_nor_false() -> None:
    sim = simulate(_step_scene(2 * SIGMA), SENSOR, seed=1)
    truth, scan = sim.truth, sim.scan
    found = truth_extraction(scan, truth)  # finds the hidden breakpoint exactly
    assert found.breakpoints.tolist() == truth.breakpoints.tolist()
    honoured = score(found, truth, scan, Tolerances(truth_dont_care=True)).breakpoints
    assert (honoured.tp, honoured.fp, honoured.fn) == (0, 0, 0)
    assert (honoured.true_dont_care, honoured.found_ignored) == (1, 1)
    counted = score(found, truth, scan, Tolerances()).breakpoints  # the default: off
    assert (counted.tp, counted.fp, counted.fn) == (1, 0, 0)


def test_missing_a_dont_care_event_is_no_false_negative() -> None:
    sim = simulate(_corner_scene(2.0), SENSOR, noise=NoiseModel(sigma=0.03), seed=2)
    truth, scan = sim.truth, sim.scan
    found = truth_extraction(scan, truth)
    missed = Extraction(
        first=found.first,
        last=found.last,
        n_points=found.n_points,
        lines=found.lines,
        covariances=found.covariances,
        breakpoints=found.breakpoints,
        corners=np.array([], np.intp),
        outliers=found.outliers,
        method="test",
        params={},
    )
    honoured = score(missed, truth, scan, Tolerances(truth_dont_care=True)).corners
    assert (honoured.tp, honoured.fp, honoured.fn, honoured.true_dont_care) == (0, 0, 0, 1)
    counted = score(missed, truth, scan, Tolerances()).corners
    assert counted.fn == 1
