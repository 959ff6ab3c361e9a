"""``scanlines eval --family``: every family sensor, the worst per figure, end to end."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from cli_helpers import Ran, scanlines
from scanlines.evaluation.family import FamilyRow, worst_rows
from scanlines.evaluation.scenes import generate_scene_set, load_scene_set
from scanlines.sim.family import CORNER_NAMES


def run(*args: str, cwd: Path) -> Ran:
    return scanlines(*args, cwd=cwd)


def test_eval_family_end_to_end(tmp_path: Path) -> None:
    done = run(
        "eval", "family", "-n", "2", "--family-count", "2", "-m", "adaptive",
        "--no-plots", "--out", "out", cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "worst sensor per figure" in done.stdout
    sensors = ["family-00", "family-01", *CORNER_NAMES]
    with (tmp_path / "out" / "family.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [(r["sensor"], r["label"]) for r in rows] == [
        (s, label) for s in sensors for label in ("adaptive", "truth")
    ]
    truth = [r for r in rows if r["label"] == "truth"]
    assert all(float(r["true_pos_ratio"]) == 1.0 for r in truth)
    assert all(float(r["false_pos_excess"]) == 0.0 for r in truth)
    assert all(r["n_scans"] == "2" for r in rows)
    with (tmp_path / "out" / "family_worst.csv").open() as handle:
        worst = list(csv.DictReader(handle))
    assert {(w["label"], w["figure"]) for w in worst} == {
        (label, f) for label in ("adaptive", "truth")
        for f in ("bp_f1", "corner_f1", "true_pos_ratio", "false_pos_excess")
    }  # fmt: skip
    assert all(w["sensor"] in sensors for w in worst)
    config = json.loads((tmp_path / "out" / "summary.json").read_text())["config"]
    assert config["clutter"] is True
    assert config["tolerances"]["truth_dont_care"] is True
    assert config["sensors"] == sensors


def test_eval_family_refuses_sensor_presets(tmp_path: Path) -> None:
    done = run("eval", "family", "-s", "tim571", "--out", "out", cwd=tmp_path)
    assert done.returncode == 2
    assert "No such option" in done.stderr


def _row(sensor: str, label: str, bp: float, corner: float, ratio: float, excess: float):
    return FamilyRow(sensor, label, 3, bp, corner, 0.9, 0.1, ratio, excess)


def test_the_worst_sensor_is_picked_per_figure_and_spec() -> None:
    rows = [
        _row("a", "m", 0.97, 0.80, 0.99, 0.02),
        _row("b", "m", 0.90, math.nan, 0.98, 0.07),
        _row("c", "m", 0.99, 0.95, 0.95, 0.00),
    ]
    worst = {w.figure: w for w in worst_rows(rows)}
    assert (worst["bp_f1"].sensor, worst["bp_f1"].value, worst["bp_f1"].met) == ("b", 0.90, False)
    assert (worst["corner_f1"].sensor, worst["corner_f1"].met) == ("a", False)  # NaN skipped
    assert (worst["true_pos_ratio"].sensor, worst["true_pos_ratio"].met) == ("c", False)
    assert (worst["false_pos_excess"].sensor, worst["false_pos_excess"].met) == ("b", False)
    fine = worst_rows([_row("a", "m", 0.96, 0.91, 0.97, 0.05)])
    assert all(w.met for w in fine)


def test_a_clutter_scene_set_keeps_its_dont_care_events(tmp_path: Path) -> None:
    made = generate_scene_set(["corner-coarse-noisy"], 3, seed=4, clutter=True)
    assert made.clutter
    assert {c.kind for c in made.cases} <= {"cluttered room", "long corridor"}
    loaded = load_scene_set(made.save(tmp_path / "set.npz"))
    assert loaded.clutter
    for a, b in zip(made.cases, loaded.cases, strict=True):
        np.testing.assert_array_equal(a.truth.breakpoint_dont_care, b.truth.breakpoint_dont_care)
        np.testing.assert_array_equal(a.truth.corner_dont_care, b.truth.corner_dont_care)
    assert any(c.truth.breakpoint_dont_care.any() for c in made.cases)
