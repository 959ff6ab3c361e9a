"""The ``truth`` row of the evaluation: the true segments fitted to their own returns."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

import scanlines
from cli_helpers import scanlines as run_command
from scanlines.errors import ParameterError
from scanlines.evaluation.evaluate import evaluate
from scanlines.evaluation.metrics import score
from scanlines.evaluation.scenes import generate_scene_set, make_scene
from scanlines.evaluation.specs import TRUTH, parse_spec, parse_specs
from scanlines.evaluation.truth_row import truth_extraction
from scanlines.sim import NoiseModel, SensorSpec, World, box, simulate, wall

SENSORS = ("lms_1deg", "tim571")


def perfect_events(summary) -> None:
    assert summary.breakpoints.tp > 0
    assert summary.corners.tp > 0
    assert summary.breakpoints.f1 == summary.corners.f1 == 1.0


@pytest.mark.parametrize("sensor", ["lms_1deg", "lms_05deg", "tim571", "urg04lx"])
def test_truth_row_has_the_true_runs_events_and_own_returns(sensor):
    case = make_scene(sensor, 1, seed=4)
    found = truth_extraction(case.scan, case.truth)
    seg = case.truth.segments
    np.testing.assert_array_equal(found.first, seg.first)
    np.testing.assert_array_equal(found.last, seg.last)
    np.testing.assert_array_equal(found.breakpoints, case.truth.breakpoints)
    np.testing.assert_array_equal(found.corners, case.truth.corners)
    own = [
        np.count_nonzero(case.truth.true_return[f : la + 1] & case.scan.valid[f : la + 1])
        for f, la in zip(seg.first, seg.last, strict=True)
    ]
    assert found.n_points.tolist() == own == seg.n_returns.tolist()
    assert found.method == TRUTH
    assert np.isfinite(found.lines).all()


def test_truth_row_scores_perfect_events_with_noise():
    result = evaluate([TRUTH], SENSORS, 3, seed=2)
    for sensor in SENSORS:
        perfect_events(result.summary(sensor, TRUTH).summary)


def test_truth_row_is_perfect_without_noise():
    result = evaluate(["adaptive", TRUTH], SENSORS, 3, seed=2, noise="exact")
    for sensor in SENSORS:
        summary = result.summary(sensor, TRUTH).summary
        perfect_events(summary)
        assert summary.segments.n_true > 0
        assert summary.segments.true_pos == 1.0
        assert summary.segments.false_pos == 0.0
        assert summary.segments.mean_abs_drho < 1e-9


def test_outliers_mixed_pixels_and_dropouts_stay_out_of_the_fit():
    # exact ranges, but many spurious returns: only a fit to the true returns is exact
    world = World([wall((4, -6), (4, 6)), box((2.0, 0.5), 0.6, 0.6)])
    noise = NoiseModel(outlier_prob=0.1, mixed_pixel_prob=1.0, dropout_prob=0.05)
    sim = simulate(world, "lms_05deg", seed=3, noise=noise)
    truth = sim.truth
    found = truth_extraction(sim.scan, truth)
    inside = np.zeros(truth.n_beams, bool)
    for f, la in zip(found.first, found.last, strict=True):
        inside[f : la + 1] = True
    assert inside[truth.outliers].any()  # the test means something
    assert len(truth.mixed_pixels) > 0
    np.testing.assert_array_equal(found.outliers, np.union1d(truth.outliers, truth.mixed_pixels))
    s = score(found, truth, sim.scan).segments
    assert s.n_true > 0
    assert (s.true_pos, s.false_pos) == (1.0, 0.0)


def test_truth_row_across_the_seam_of_a_full_circle():
    ring = SensorSpec("ring", 360, math.radians(-179.5), math.radians(1.0), 0.0, 30.0)
    room = box((0, 0), 4.0, 4.0, angle=math.radians(0.2), kind="room")
    sim = simulate(World([room]), ring, noise=NoiseModel())
    found = truth_extraction(sim.scan, sim.truth)
    assert (found.first[-1], found.last[-1]) == (315, 44)  # across the seam, listed last
    np.testing.assert_allclose(found.lines[:, 0], 2.0, atol=1e-9)
    s = score(found, sim.truth, sim.scan)
    assert (s.segments.true_pos, s.segments.false_pos, s.corners.f1) == (1.0, 0.0, 1.0)


def test_truth_is_a_spec_but_not_a_method():
    assert TRUTH not in scanlines.method_names()
    with pytest.raises(ParameterError, match="unknown method 'truth'"):
        scanlines.Extractor(TRUTH)
    spec = parse_spec("truth@ceiling")
    assert (spec.method, spec.label, spec.is_truth) == (TRUTH, "ceiling", True)
    assert spec.to_dict()["resolved"] == {}
    with pytest.raises(ParameterError, match="no extractor"):
        spec.extractor()
    for text in ("truth:paper", "truth?k=3"):
        with pytest.raises(ParameterError, match="takes no preset or parameters"):
            parse_spec(text)
    assert [s.label for s in parse_specs(["adaptive", "truth"])] == ["adaptive", TRUTH]


def test_truth_row_in_workers_and_on_scene_sets():
    scenes = generate_scene_set(["urg04lx"], 2, seed=1)
    alone = evaluate([TRUTH], scenes=scenes)
    parallel = evaluate(["adaptive", TRUTH], ["urg04lx"], 2, seed=1, workers=2)
    rows = [r.score.to_dict() for r in alone.records]
    assert rows == [r.score.to_dict() for r in parallel.records if r.spec.is_truth]


def test_eval_command_with_the_truth_row(tmp_path):
    args = [
        "eval",
        "sim",
        "-m",
        "adaptive",
        "-m",
        "truth",
        "-s",
        "lms_1deg",
        "-n",
        "2",
        "--seed",
        "3",
    ]
    out = run_command(*args, "--worst", "1", "--out", tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "worst.png").stat().st_size > 0
    with (tmp_path / "summary.csv").open(newline="") as handle:
        rows = {row["label"]: row for row in csv.DictReader(handle)}
    assert set(rows) == {"adaptive", TRUTH}
    assert rows[TRUTH]["n_scans"] == "2"
    assert float(rows[TRUTH]["bp_f1"]) == float(rows[TRUTH]["corner_f1"]) == 1.0
    assert float(rows[TRUTH]["seg_true_pos"]) > 0.5
    table = [line for line in out.stdout.splitlines() if line.strip().startswith(TRUTH)]
    assert len(table) == 1
