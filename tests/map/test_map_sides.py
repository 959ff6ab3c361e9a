"""Walls with a side: map lines keep the side their returns came from (fusion, the JSON map
and its reader), and the filter matches a return only to a face seen from its side."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines.map import build_map
from scanlines.map.align import LineSet
from scanlines.map.export import write_map
from scanlines.map.filter import FilterSettings, LineMapFilter
from scanlines.map.fusion import BACK, BOTH, FRONT
from scanlines.map.localize import MapFileError, read_line_map
from test_map import view
from test_map_align import room_lines

#: A wall 10 cm thick: its lower face at y = 2.0, its upper face at y = 2.1.
THICK = [((-3.0, 2.0), (6.0, 2.0)), ((-3.0, 2.1), (6.0, 2.1))]
#: A wall of no thickness (a board), seen from both sides.
BOARD = [((-3.0, 2.0), (6.0, 2.0))]


def mapped(walls, poses):
    scans = [view(walls, pose, seed=k, sigma=0.002) for k, pose in enumerate(poses)]
    return build_map(enumerate(scans)).line_map.lines()


BELOW = [(0.2 * k, 0.0, 1.2) for k in range(6)]
ABOVE = [(0.2 * k, 4.0, -1.6) for k in range(6)]


def test_the_two_faces_of_a_thin_wall_are_two_lines_each_seen_from_its_side():
    lines = mapped(THICK, BELOW + ABOVE)
    assert len(lines) == 2
    lower, upper = np.argsort(lines.rho * np.sign(np.sin(lines.alpha)))
    # normals point away from the origin (+y): the lower face is seen from below (the other
    # side of its normal), the upper one from above (its normal's side)
    assert lines.rho[lower] == pytest.approx(2.0, abs=0.01)
    assert lines.sides[lower] == BACK
    assert lines.rho[upper] == pytest.approx(2.1, abs=0.01)
    assert lines.sides[upper] == FRONT


def test_a_board_seen_from_both_sides_is_one_line_seen_from_both():
    lines = mapped(BOARD, BELOW + ABOVE)
    assert len(lines) == 1
    assert lines.sides[0] == BOTH
    assert mapped(BOARD, BELOW).sides[0] == BACK


def test_the_json_map_keeps_the_side_and_an_older_map_reads_as_both(tmp_path):
    lines = mapped(THICK, BELOW + ABOVE)
    path = write_map(lines, tmp_path / "thick.json", overwrite=False)
    document = json.loads(path.read_text())
    assert sorted(r["seen_from"] for r in document["lines"]) == ["normal side", "other side"]
    read, _ = read_line_map(path)
    assert sorted(read.sides.tolist()) == sorted(lines.sides.tolist())
    for record in document["lines"]:
        del record["seen_from"]
    older = tmp_path / "older.json"
    older.write_text(json.dumps(document))
    assert read_line_map(older)[0].sides.tolist() == [BOTH, BOTH]


def test_a_bad_side_is_named_with_its_file_line_and_field(tmp_path):
    path = write_map(mapped(BOARD, BELOW), tmp_path / "m.json", overwrite=False)
    document = json.loads(path.read_text())
    document["lines"][0]["seen_from"] = "inside"
    path.write_text(json.dumps(document))
    with pytest.raises(MapFileError, match=r"m.json: line 0: field seen_from: 'inside' is not"):
        read_line_map(path)
    ran = scanlines("localize", tmp_path / "nowhere.clf", "--map", path, "--out",
                    tmp_path / "p.tum")  # fmt: skip
    assert ran.returncode != 0
    assert "Traceback" not in ran.stderr


def _one_wall(sides: int) -> LineSet:
    lines = room_lines(BOARD)
    return LineSet(*lines[:4], np.array([sides]))


@pytest.mark.parametrize(("sides", "matched"), [(BACK, True), (BOTH, True), (FRONT, False)])
def test_a_return_matches_a_face_only_from_a_side_it_was_seen_from(sides, matched):
    scan = view(BOARD, (0.0, 0.0, 1.2), seed=1, sigma=0.002)  # from below: the back
    tracker = LineMapFilter(_one_wall(sides), FilterSettings(sides=True))
    tracker.start((0.0, 0.02, 1.2))
    step = tracker.step(scan.points[scan.valid], None)
    assert (step.pairs > 0) == matched
    if matched:
        assert step.pose[1] == pytest.approx(0.0, abs=0.005)


def test_sides_are_ignored_by_default():
    scan = view(BOARD, (0.0, 0.0, 1.2), seed=1, sigma=0.002)
    tracker = LineMapFilter(_one_wall(FRONT))
    tracker.start((0.0, 0.02, 1.2))
    assert tracker.step(scan.points[scan.valid], None).pairs > 0
