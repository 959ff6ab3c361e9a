"""A line map read by ``localize`` is data to distrust: coordinates finite and within the
map's limits, ``rho`` and ``alpha`` consistent with the ends, covariances 2 x 2,
symmetric and positive semi-definite, booleans no numbers, deep nesting refused; each a
one-line :class:`MapFileError` (exit 2 from the command). And a scan whose every weight
vanished (a map line's ``rho`` of 1e308 given to the filter directly) is not "aligned"."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines.data import sample
from scanlines.map.align import LineSet
from scanlines.map.filter import LineMapFilter
from scanlines.map.localize import MapFileError, localize, read_line_map
from test_localize import room_map
from test_map_tracking import drifting_log


@pytest.fixture(scope="module")
def room(tmp_path_factory) -> dict:
    """The room's map as a JSON document (written by ``write_map``)."""
    return json.loads(room_map(tmp_path_factory.mktemp("room")).read_text())


def every_line(document: dict, name: str, value) -> dict:
    changed = json.loads(json.dumps(document))
    for line in changed["lines"]:
        line[name] = value(line) if callable(value) else value
    return changed


def one_line(document: dict, k: int, name: str, value) -> dict:
    changed = json.loads(json.dumps(document))
    changed["lines"][k][name] = value
    return changed


def refused(tmp_path, document_or_text, *words: str) -> str:
    """The one-line error of ``read_line_map`` on the document (or raw text)."""
    path = tmp_path / "bad.json"
    text = document_or_text
    if not isinstance(text, str):
        text = json.dumps(document_or_text)  # NaN written as NaN: json's default
    path.write_text(text)
    with pytest.raises(MapFileError) as caught:
        read_line_map(path)
    message = str(caught.value)
    assert len(message.splitlines()) == 1
    assert len(message) < 300, message
    for word in ("bad.json", *words):
        assert word in message, message
    return message


def test_the_room_map_reads(room, tmp_path):
    path = tmp_path / "room.json"
    path.write_text(json.dumps(room))
    lines, _ = read_line_map(path)
    assert len(lines.rho) == len(room["lines"])


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("start", [1e308, 1e308], "beyond the map's limit |x|, |y| <= 1e9 m"),
        ("end", [2e5, 0.0], "beyond the map's limit of 1e5 m"),
        ("start", [True, False], "not a pair of numbers"),
        ("end", [1.0, 2.0, 3.0], "not a pair of numbers"),
        ("rho", True, "field rho: missing or not a number"),
        ("rho", 1e308, "fields rho, alpha: the line does not pass through its ends"),
        ("alpha", 1.0e3, "fields rho, alpha: the line does not pass through its ends"),
        ("covariance", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "not a 2 x 2 matrix"),
        ("covariance", [[-1.0, 0.0], [0.0, 1.0]], "not positive semi-definite"),
        ("covariance", [[1.0, 0.5], [0.0, 1.0]], "not symmetric"),
        ("seen_from", "inside", "field seen_from: 'inside' is not one of"),
        ("seen_from", ["normal side"], "field seen_from: ['normal side'] is not one of"),
        ("seen_from", True, "field seen_from: True is not one of"),
        ("covariance", [[1.0, False], [False, 1.0]], "not a 2 x 2 matrix of numbers"),
        ("covariance", [[1.0, 0.0], [0.0, "nan"]], "not a 2 x 2 matrix of numbers"),
        ("covariance", [[10**400, 0], [0, 1]], "not finite"),
        ("rho", 10**400, "field rho: not finite"),
        ("start", [10**400, 0], "field start: not finite"),
    ],
    ids=[
        "ends at 1e308", "end far out", "boolean start", "three numbers", "boolean rho",
        "rho 1e308", "alpha off", "3x3 covariance", "negative covariance",
        "asymmetric covariance", "unknown side", "side in a list", "boolean side",
        "boolean covariance", "string covariance",
        "covariance beyond a double", "rho beyond a double", "start beyond a double",
    ],
)  # fmt: skip
def test_a_bad_line_is_named_in_one_line(room, tmp_path, name, value, words):
    refused(tmp_path, one_line(room, 3, name, value), "line 3", words)


def test_a_nan_or_far_origin_is_refused(room, tmp_path):
    document = json.loads(json.dumps(room))
    document["frame"]["origin"] = [math.nan, 0.0]
    refused(tmp_path, document, "field frame.origin", "not finite")
    document["frame"]["origin"] = [2e9, 0.0]
    refused(tmp_path, document, "field frame.origin", "1e9 m")
    document["frame"]["origin"] = [False, 0.0]
    refused(tmp_path, document, "field frame.origin")


def test_deep_nesting_and_huge_integers_are_refused(room, tmp_path):
    refused(tmp_path, "[" * 100_000 + "]" * 100_000, "nested more than 64 deep")
    text = json.dumps(room).replace('"scans": ', '"scans": ' + "1" * 5000 + ', "x": ', 1)
    refused(tmp_path, text, "4300 digits")


def test_every_rho_at_1e308_with_the_ends_intact_is_refused(room, tmp_path):
    refused(
        tmp_path,
        every_line(room, "rho", 1e308),
        "line 0",
        "fields rho, alpha: the line does not pass through its ends",
    )


def test_the_command_refuses_a_bad_map_in_one_line(room, tmp_path):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(every_line(room, "rho", 1e308)))
    done = scanlines("localize", sample("intel"), "--map", path,
                     "--initial-pose", "0,0,0,0", "--out", tmp_path / "p.tum")  # fmt: skip
    assert done.returncode == 2, done.stderr[-2000:]
    (line,) = done.stderr.strip().splitlines()
    assert "m.json: line 0: fields rho, alpha: the line does not pass through its ends" in line


def test_a_scan_whose_weights_all_vanish_is_not_aligned(room, tmp_path):
    """Map lines given to the filter directly (no file), every ``rho`` at 1e308: each
    residual's weight is 0 and the step cannot move; it must not say "aligned"."""
    path = tmp_path / "room.json"
    path.write_text(json.dumps(room))
    lines, frame = read_line_map(path)
    scans, truth = drifting_log(12)
    good = localize(enumerate(scans), lines, frame, (scans[0].timestamp, tuple(truth[0])))
    assert good.not_fit == 0
    far = LineSet(np.full_like(lines.rho, 1e308), lines.alpha, lines.start, lines.end)
    run = localize(enumerate(scans), far, frame, (scans[0].timestamp, tuple(truth[0])))
    assert run.not_fit == len(run.tracked)
    assert all(t.pose == t.predicted for t in run.tracked)
    tracker = LineMapFilter(far)
    tracker.start(frame.pose(truth[0]))
    step = tracker.step(scans[0].points[scans[0].valid], None)
    assert step.status == "too few returns on map lines"
