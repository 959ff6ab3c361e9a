"""The default adaptive method on a fixed, seeded simulated set: a regression guard.

The issue's targets (breakpoint F1 >= 0.95, corner F1 >= 0.90, TruePos >= 0.92, FalsePos <=
0.10 on every sensor) are NOT all reached; ``docs/decisions/README.md`` gives the 300-scene
numbers, ``ceiling.md`` and ``events.md`` there the reasons. These floors sit a little below
what the default measured on this set (40 scenes per sensor, seed 7, realistic noise), so that
a regression shows; the measured values are in the comments.
"""

from __future__ import annotations

import pytest

from scanlines.evaluation.evaluate import evaluate
from scanlines.evaluation.specs import parse_specs

pytestmark = pytest.mark.slow  # 300 scenes per sensor

# sensor: (bp F1, corner F1, TruePos, FalsePos ceiling); measured 2026-11-25:
# lms_1deg 0.942 0.877 0.975 0.045 | lms_05deg 0.947 0.867 0.918 0.089
# tim571   0.945 0.802 0.690 0.313 | urg04lx   0.908 0.749 0.710 0.328
FLOORS = {
    "lms_1deg": (0.92, 0.84, 0.95, 0.07),
    "lms_05deg": (0.93, 0.83, 0.90, 0.10),
    "tim571": (0.92, 0.76, 0.65, 0.35),
    "urg04lx": (0.88, 0.71, 0.67, 0.36),
}


@pytest.fixture(scope="module")
def result():
    return evaluate(parse_specs(["adaptive"]), sensors=list(FLOORS), n=40, seed=7)


@pytest.mark.parametrize("sensor", list(FLOORS))
def test_default_stays_above_its_measured_floor(result, sensor):
    scores = result.summary(sensor, "adaptive").summary.to_dict()
    bp, corner, true_pos, false_pos = FLOORS[sensor]
    assert scores["bp_f1"] >= bp
    assert scores["corner_f1"] >= corner
    assert scores["seg_true_pos"] >= true_pos
    assert scores["seg_false_pos"] <= false_pos


def test_default_beats_the_literal_paper_everywhere(result):
    paper = evaluate(parse_specs(["adaptive:paper"]), sensors=["lms_1deg"], n=10, seed=7)
    literal = paper.summary("lms_1deg", "adaptive:paper").summary.to_dict()
    default = result.summary("lms_1deg", "adaptive").summary.to_dict()
    assert default["bp_f1"] > literal["bp_f1"] + 0.3
    assert default["corner_f1"] > literal["corner_f1"] + 0.3
