"""Hand labels of the three real sensors and the scores on them (`scanlines eval --labels`)."""

from __future__ import annotations

import csv

import pytest
from typer.testing import CliRunner

from scanlines.cli import app
from scanlines.data.labels import LABEL_FILES, label_set, labelled_samples
from scanlines.evaluation.labelled import evaluate_labelled


@pytest.mark.parametrize("name", list(LABEL_FILES))
def test_every_sensor_has_twenty_frames_and_forty_corners(name):
    labels = label_set(name)  # validated against the shipped log
    assert len(labels.frames) >= 20
    assert sum(len(frame.corners) for frame in labels.frames) >= 40
    assert "no extraction method" in labels.labeller or "no method" in labels.labeller


def test_the_labels_are_installed():
    assert labelled_samples() == tuple(LABEL_FILES)


def test_scores_on_the_labels_are_rates_and_counts():
    result = evaluate_labelled(["iepf"], ["urg"])
    (row,) = result.rows()
    assert row["frames"] == 20
    for key in ("bp_P", "bp_R", "bp_F1", "coverage", "short_share"):
        assert 0.0 <= row[key] <= 1.0
    assert row["segments_per_scan"] > 1


def test_eval_labels_command_writes_a_table(tmp_path):
    result = CliRunner().invoke(
        app, ["eval", "labels", "urg", "-m", "iepf", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader((tmp_path / "labelled.csv").open()))
    assert [r["sample"] for r in rows] == ["urg"]
    bad = CliRunner().invoke(app, ["eval", "labels", "mars", "--out", str(tmp_path)])
    assert bad.exit_code == 2
    assert "no hand labels for mars" in bad.output
    segments = CliRunner().invoke(app, ["eval", "labels", "urg", "--tol-alpha", "3"])
    assert segments.exit_code == 2
    assert "--tol-alpha" in segments.output
