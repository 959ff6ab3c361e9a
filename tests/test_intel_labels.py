"""The hand labels of thirty Intel excerpt frames (scanlines/data/intel_labels.json).

These tests check the file against the shipped log and against its own written rule;
they never run an extraction method.
"""

from __future__ import annotations

import json
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest

from scanlines.data import sample
from scanlines.data.labels import (
    INTEL_LABELS,
    LabelError,
    LabelledFrame,
    intel_label_rule,
    intel_label_set,
    intel_labels,
    read_labels,
)
from scanlines.io import open_log

SCANS = (
    *(1, 13, 23, 35, 52, 57, 62, 67, 73, 83, 94, 111, 122, 132, 142, 153, 164, 175, 185),
    *(195, 212, 226, 236, 247, 257, 267, 275, 281, 289, 297),
)


@pytest.fixture(scope="module")
def scans():
    return list(open_log(sample("intel")))


@pytest.fixture(scope="module")
def frames():
    return intel_labels()


def _all_labelled(frame: LabelledFrame) -> dict[str, tuple[int, ...]]:
    return {
        "breakpoints": frame.breakpoints,
        "corners": frame.corners,
        "uncertain_breakpoints": frame.uncertain_breakpoints,
        "uncertain_corners": frame.uncertain_corners,
    }


def _next_return(valid: np.ndarray, beam: int) -> int | None:
    after = np.flatnonzero(valid[beam + 1 :])
    return None if after.size == 0 else beam + 1 + int(after[0])


def _prev_return(valid: np.ndarray, beam: int) -> int | None:
    before = np.flatnonzero(valid[:beam])
    return None if before.size == 0 else int(before[-1])


# --- the file ----------------------------------------------------------------------------


def test_file_is_in_the_package_and_loads(frames) -> None:
    assert INTEL_LABELS.is_file()
    assert INTEL_LABELS.parent == Path(sample("intel")).parent
    assert all(isinstance(f, LabelledFrame) for f in frames)
    labels = intel_label_set()
    assert labels.source == "intel_excerpt.clf.gz"
    assert labels.beams == 180
    assert labels.angle_convention == "step"
    assert labels.labeller == "by hand from plots, no extraction method consulted"


def test_thirty_frames_with_the_chosen_scan_indices(frames) -> None:
    assert tuple(f.scan for f in frames) == SCANS


def test_frames_are_immutable(frames) -> None:
    with pytest.raises(AttributeError):
        frames[0].scan = 1  # type: ignore[misc]
    assert isinstance(frames[0].breakpoints, tuple)
    assert intel_labels() is not intel_labels()  # callers get their own list


def test_rule_text_is_the_written_rule() -> None:
    rule = intel_label_rule()
    for needle in (
        "last valid beam before a discontinuity",
        "a run of two or more beams with no return",
        "a single missing beam between them does not count as a gap",
        "first and last beams are not breakpoints",
        "roughly 20 deg or more",
        "at least 3 returns",
        "nearest the vertex",
        "no corners",
        "don't care",
    ):
        assert needle in rule


def test_how_chosen_reproduces_the_frames(scans) -> None:
    """The frame choice written in the file, recomputed from the raw ranges."""
    counts = []
    for scan in scans:
        ranges = scan.ranges[scan.valid]
        counts.append(int(np.sum(np.abs(np.diff(ranges)) > 0.3)))
    order = sorted(range(len(scans)), key=lambda i: (-counts[i], i))
    kept: list[int] = []
    for spacing, most in ((20, 10), (20, None), (10, None), (5, 4)):
        added = 0
        for i in order:
            if most is not None and added == most:
                break
            if all(abs(i - j) >= spacing for j in kept):
                kept.append(i)
                added += 1
    assert tuple(sorted(kept)) == SCANS
    assert "0.3 m" in intel_label_set().how_chosen
    assert "at least 20" in intel_label_set().how_chosen


def test_notes_are_written(frames) -> None:
    assert all(len(f.notes) > 40 for f in frames)


# --- the labels against the log -----------------------------------------------------------


def test_every_labelled_beam_is_a_valid_return(scans, frames) -> None:
    for frame in frames:
        valid = scans[frame.scan].valid
        for key, beams in _all_labelled(frame).items():
            bad = [b for b in beams if not valid[b]]
            assert not bad, f"scan {frame.scan} {key}: no return at {bad}"


def test_lists_are_sorted_and_certain_disjoint_from_uncertain(frames) -> None:
    for frame in frames:
        for beams in _all_labelled(frame).values():
            assert list(beams) == sorted(set(beams))
        assert not set(frame.breakpoints) & set(frame.uncertain_breakpoints)
        assert not set(frame.corners) & set(frame.uncertain_corners)
        # a beam is either the end of a run or a vertex inside one
        assert not set(frame.corners) & set(frame.breakpoints)


def test_breakpoints_are_followed_by_a_gap_or_a_range_change(scans, frames) -> None:
    """Kind (a): two or more missing beams follow; kind (b): the next return differs."""
    for frame in frames:
        scan = scans[frame.scan]
        for beam in frame.breakpoints:
            assert 0 < beam < len(scan) - 1, f"scan {frame.scan}: breakpoint at an end beam"
            nxt = _next_return(scan.valid, beam)
            assert nxt is not None, f"scan {frame.scan}: breakpoint {beam} has no next return"
            gap = nxt - beam - 1
            jump = abs(scan.ranges[nxt] - scan.ranges[beam])
            assert gap >= 2 or jump > 0.05, (
                f"scan {frame.scan}: breakpoint {beam} has {gap} missing beam(s) after it and "
                f"a range change of only {jump:.2f} m"
            )


def test_every_gap_of_two_or_more_missing_beams_is_a_breakpoint(scans, frames) -> None:
    """Kind (a) is mechanical: no gap may be left unlabelled or uncertain."""
    for frame in frames:
        scan = scans[frame.scan]
        returns = np.flatnonzero(scan.valid)
        for a, b in pairwise(returns):
            if b - a - 1 >= 2:
                assert a in frame.breakpoints, f"scan {frame.scan}: gap after beam {a}"


def test_single_missing_beams_alone_are_not_breakpoints(scans, frames) -> None:
    """A breakpoint before a single missing beam needs a range change (kind (b))."""
    for frame in frames:
        scan = scans[frame.scan]
        for beam in frame.breakpoints:
            nxt = _next_return(scan.valid, beam)
            if nxt == beam + 2:
                assert abs(scan.ranges[nxt] - scan.ranges[beam]) > 0.05


def _run_side(valid: np.ndarray, corner: int, stops: set[int], step: int) -> list[int]:
    """Valid returns from ``corner`` outwards (``step`` -1 or +1) within its run: the run
    ends at a gap of two or more missing beams and after a (certain or uncertain)
    breakpoint."""
    side: list[int] = []
    prev = corner
    for i in range(corner + step, -1 if step < 0 else valid.size, step):
        if not valid[i]:
            continue
        if abs(i - prev) - 1 >= 2:
            break
        if (i if step < 0 else prev) in stops:
            break
        side.append(i)
        prev = i
    return side


def test_corners_have_three_returns_on_each_side_within_their_run(scans, frames) -> None:
    for frame in frames:
        valid = scans[frame.scan].valid
        stops = set(frame.breakpoints) | set(frame.uncertain_breakpoints)
        for corner in frame.corners:
            left = _run_side(valid, corner, stops, -1)
            right = _run_side(valid, corner, stops, +1)
            where = f"scan {frame.scan}: corner {corner}"
            assert len(left) >= 3, f"{where}: {len(left)} returns before it in its run"
            assert len(right) >= 3, f"{where}: {len(right)} returns after it in its run"


def _line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre)
    return centre, vt[0], vt[1]


def test_corners_are_turns_between_straight_sides_at_the_nearest_beam(scans, frames) -> None:
    """With the 3 returns on each side (the rule's minimum): both sides straight within
    2.5 cm (the ranges are stored to 1 cm), a turn of at least 20 deg, and the labelled
    beam within one beam of the return nearest the lines' intersection (the labeller
    fitted longer lines by hand, conventions 5 and 6 of the rule)."""
    for frame in frames:
        scan = scans[frame.scan]
        valid, points = scan.valid, scan.points
        for corner in frame.corners:
            left = [i for i in range(corner - 1, -1, -1) if valid[i]][:3]
            right = [i for i in range(corner + 1, valid.size) if valid[i]][:3]
            c1, d1, n1 = _line(points[left])
            c2, d2, n2 = _line(points[right])
            assert np.abs((points[left] - c1) @ n1).max() < 0.025
            assert np.abs((points[right] - c2) @ n2).max() < 0.025
            turn = np.degrees(np.arccos(min(1.0, abs(float(d1 @ d2)))))
            assert turn >= 20, f"scan {frame.scan}: corner {corner} turns {turn:.1f} deg"
            t = np.linalg.solve(np.column_stack([d1, -d2]), c2 - c1)
            vertex = c1 + t[0] * d1
            around = [i for i in (left[0], corner, right[0]) if i is not None]
            nearest = min(around, key=lambda i: np.linalg.norm(points[i] - vertex))
            if nearest != corner:  # then the next return beyond must not be nearer still
                beyond = (
                    _prev_return(valid, nearest)
                    if nearest < corner
                    else _next_return(valid, nearest)
                )
                assert beyond is None or np.linalg.norm(points[beyond] - vertex) > np.linalg.norm(
                    points[nearest] - vertex
                ), f"scan {frame.scan}: corner {corner} is more than one return off the vertex"


# --- validation errors --------------------------------------------------------------------


def _write(tmp_path: Path, edit) -> Path:
    doc = json.loads(INTEL_LABELS.read_text(encoding="utf-8"))
    edit(doc)
    path = tmp_path / "labels.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _scan13(doc) -> dict:
    return next(frame for frame in doc["frames"] if frame["scan"] == 13)


def _frame0(key: str, value):
    """An edit of the frame of scan 13."""

    def edit(doc):
        _scan13(doc)[key] = value

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_frame0("breakpoints", [63, 200]), r"breakpoints: beam 200 out of range 0\.\.179"),
        (_frame0("corners", [102, 71]), r"corners not sorted at beam 71"),
        (_frame0("corners", [71, 71]), r"corners repeated at beam 71"),
        (_frame0("breakpoints", [63, 70.5]), r"breakpoints must hold integers"),
        (_frame0("uncertain_corners", [71]), r"beam\(s\) \[71\] are in both corners"),
        (_frame0("breakpoints", [0, 63]), r"first or last beam \[0\]"),
        (_frame0("scan", -1), r"scan must be a non-negative integer"),
        (_frame0("colour", "red"), r"unknown key\(s\) colour"),
        (lambda doc: _scan13(doc).pop("notes"), r"missing key\(s\) notes"),
        (lambda doc: doc.pop("rule"), r"missing key\(s\) rule"),
        (lambda doc: doc["frames"].append(_scan13(doc)), r"scan 13 is labelled twice"),
    ],
)
def test_malformed_files_raise_clear_errors(tmp_path, edit, message) -> None:
    with pytest.raises(LabelError, match=message):
        read_labels(_write(tmp_path, edit))


def test_labels_on_beams_without_a_return_are_rejected(tmp_path, scans) -> None:
    valid = [scan.valid for scan in scans]
    path = _write(tmp_path, _frame0("breakpoints", [63, 84]))  # scan 13 beam 84: no return
    read_labels(path)  # the layout alone is fine
    with pytest.raises(
        LabelError, match=r"scan 13\): breakpoints: beam\(s\) \[84\] have no return"
    ):
        read_labels(path, valid)
    with pytest.raises(LabelError, match="the log has only 10 scans"):
        read_labels(INTEL_LABELS, valid[:10])


def test_label_error_is_a_value_error(tmp_path) -> None:
    path = tmp_path / "broken.json"
    path.write_text("{not json", encoding="utf-8")
    with pytest.raises(ValueError, match="cannot read label file"):
        read_labels(path)
