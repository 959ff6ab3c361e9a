"""A map does not depend on where the world's origin is (scanlines.map.frame): the shipped
excerpts shifted by up to 10^8 m give the same lines and the same held-out score;
coordinates beyond the limit are refused in one line; the spatial index's work is bounded
whatever the extent."""

from __future__ import annotations

import json
import math
import time
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from map_shift import shifted_sample
from scanlines import Extractor
from scanlines.cli.commands import app
from scanlines.io import open_log
from scanlines.map import FusionSettings, LineMap, build_map
from scanlines.map.holdout import evaluate_map

OFFSETS = (0.0, 1e4, 1e5, 5e6, 1e7, 1e8)


@pytest.fixture(scope="module")
def extractor() -> Extractor:
    return Extractor()


def mapped(path, extractor):
    with open_log(path) as reader:
        return build_map(reader.enumerate(), extractor, source=path.name)


@pytest.mark.parametrize("name", ["intel", "freiburg"])
def test_the_same_trajectory_shifted_by_a_constant_gives_the_same_map(name, tmp_path, extractor):
    """Before: 117, 165, 183 and 75 lines at 0, 1e4, 1e5 and 5e6 m (Intel)."""
    reference = None
    for offset in OFFSETS:
        build = mapped(shifted_sample(name, offset, tmp_path), extractor)
        lines = build.line_map.lines()
        assert build.frame.origin == (lines.origin[0], lines.origin[1])
        if reference is None:
            reference = lines
            assert len(lines) > 50
            continue
        assert len(lines) == len(reference), offset
        for mine, theirs in ((lines.world_start, reference.world_start),
                             (lines.world_end, reference.world_end)):  # fmt: skip
            np.testing.assert_allclose(mine - offset, theirs, rtol=0, atol=1e-6)
        np.testing.assert_allclose(lines.rho, reference.rho, rtol=0, atol=1e-6)
        np.testing.assert_allclose(lines.alpha, reference.alpha, rtol=0, atol=1e-7)
        assert lines.scans.tolist() == reference.scans.tolist()
        assert lines.segments.tolist() == reference.segments.tolist()
        assert lines.origin == (reference.origin[0] + offset, reference.origin[1] + offset)


def test_the_held_out_score_is_the_same_at_every_offset(tmp_path, extractor):
    """Before: coverage 0.79 at the origin, 0.22 at 1e4 m, 0.13 at 1e5 m, 0.01 at 5e6 m."""
    scores = []
    for offset in OFFSETS:
        path = shifted_sample("intel", offset, tmp_path)
        score, _ = evaluate_map(
            lambda path=path: open_log(path), extractor, lambda r: 0.005 + 0.0005 * r
        )
        scores.append(score)
    first = scores[0]
    assert first.coverage > 0.75
    for score in scores[1:]:
        assert score.coverage == pytest.approx(first.coverage, abs=1e-9)
        assert score.median_distance == pytest.approx(first.median_distance, abs=1e-6)
        assert score.lines == first.lines
        assert score.map_length == pytest.approx(first.map_length, abs=1e-6)


def test_eval_map_scores_the_same_at_a_utm_northing(tmp_path):
    runner = CliRunner()
    scores = []
    for offset in (0.0, 5e6):
        log = shifted_sample("intel", offset, tmp_path)
        out = tmp_path / f"eval-{offset:g}"
        done = runner.invoke(app, ["eval", "map", str(log), "--scans", "150", "--out", str(out)])
        assert done.exit_code == 0, done.output
        scores.append(json.loads((out / "map_eval.json").read_text()))
    for key in ("coverage", "lines", "segments_per_line", "loop_lines"):
        assert scores[1][key] == scores[0][key], key
    for key in ("median_distance", "map_length"):
        assert scores[1][key] == pytest.approx(scores[0][key], abs=1e-6), key
    assert scores[1]["origin"] == [scores[0]["origin"][0] + 5e6, scores[0]["origin"][1] + 5e6]


@pytest.mark.parametrize("offset", [1e9 + 1.0, 1e15])
def test_coordinates_beyond_the_limit_are_refused_in_one_line(tmp_path, offset):
    """Before: from 1e9 m a 71-line ArrayMemoryError traceback (11.5 PiB)."""
    log = shifted_sample("intel", offset, tmp_path)
    runner = CliRunner()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        done = runner.invoke(app, ["map", str(log), "--out", str(tmp_path / "map.geojson")])
        scored = runner.invoke(app, ["eval", "map", str(log), "--out", str(tmp_path / "e")])
    for result in (done, scored):
        assert result.exit_code == 2, result.output
        errors = [line for line in result.stderr.splitlines() if "error" in line.lower()]
        assert errors == [result.stderr.strip().splitlines()[-1]]
        assert errors[0].startswith(f"scanlines: error: {log}: scan 0: the pose's x = ")
        assert "beyond the map's limit |x| <= 1e9 m" in errors[0]
        assert "Warning" not in result.stderr
    assert not (tmp_path / "map.geojson").exists()


def test_a_log_at_1e8_m_maps_as_fast_as_at_the_origin(tmp_path, extractor):
    """Before: past 120 s and 777 MB. Processor time of this process, the two logs
    interleaved (origin, far, origin), so that a busy machine slows both alike."""
    paths = [shifted_sample("intel", offset, tmp_path) for offset in (0.0, 1e8, 0.0)]
    seconds = []
    for path in paths:
        started = time.process_time()
        mapped(path, extractor).line_map.lines()
        seconds.append(time.process_time() - started)
    at_origin = min(seconds[0], seconds[2])
    assert seconds[1] < 3 * at_origin + 1.0, seconds


def test_a_pose_or_segment_beyond_the_extent_names_the_source_and_scan():
    from scanlines import extract
    from scanlines.geometry.transform import to_world
    from scanlines.map.frame import MapError
    from test_map import view

    walls = [((-3.0, 2.0), (6.0, 2.0)), ((6.0, -3.0), (6.0, 2.0))]
    scan = view(walls, (0.0, 0.0, 0.0), seed=1)
    poses = iter([(5.3, 0.0, 0.0), (5.0, 1.5e5, 0.0)])
    with pytest.raises(
        MapError,
        match=r"^run\.log: scan 1: the pose is 150000 m from the map's "
        r"origin \(the first pose, at 5\.0, 0\.0\), beyond the map's limit of 1e5",
    ):
        build_map([(0, scan), (1, scan)], poses=lambda i, s: next(poses), source="run.log")
    with pytest.raises(MapError, match=r"^scan 0: the pose's y is not finite"):
        build_map([(0, scan)], poses=lambda i, s: (0.0, math.nan, 0.0))
    pose = (-2e5, 0.0, 0.0)
    with pytest.raises(MapError, match=r"^scan 7: a segment ends 2000\d\d m from the map's"):
        LineMap().add(to_world(extract(scan), pose), 7, pose)


def test_the_local_frame_is_the_first_pose_rounded_to_the_metre():
    from scanlines.map.frame import frame_at

    assert frame_at((1e7 + 0.274, -13.486, 2.0)).origin == (1e7, -13.0)
    assert frame_at((-0.4, 0.2, 0.0)).origin == (0.0, 0.0)
    assert math.copysign(1.0, frame_at((-0.4, 0.2, 0.0)).x0) == 1.0


def brute_pairs(queries, boxes):
    q, b = np.nonzero(
        (boxes[None, :, 0] <= queries[:, None, 2]) & (boxes[None, :, 2] >= queries[:, None, 0])
        & (boxes[None, :, 1] <= queries[:, None, 3]) & (boxes[None, :, 3] >= queries[:, None, 1])
    )  # fmt: skip
    return sorted(zip(q.tolist(), b.tolist(), strict=True))


def random_boxes(rng, n, spread, size):
    low = rng.uniform(-spread, spread, (n, 2))
    return np.hstack((low, low + rng.uniform(0, size, (n, 2))))


@pytest.mark.parametrize("spread", [20.0, 1e9])
def test_the_spatial_index_finds_every_overlapping_pair(spread):
    from scanlines.map.grid import box_pairs

    rng = np.random.default_rng(3)
    queries = random_boxes(rng, 300, spread, spread / 5)
    boxes = random_boxes(rng, 400, spread, spread / 5)
    q, b = box_pairs(queries, boxes)
    assert sorted(zip(q.tolist(), b.tolist(), strict=True)) == brute_pairs(queries, boxes)


def test_the_spatial_index_bounds_its_cells_for_a_huge_box():
    """A line 10^9 m long (and 10^9 m wide a box) among small ones: before, 10^17 cells."""
    from scanlines.map.grid import CELLS_PER_BOX, _Grid, box_pairs

    rng = np.random.default_rng(4)
    boxes = np.vstack((random_boxes(rng, 500, 50.0, 3.0), [[-1e9, -1e9, 1e9, 1e9]]))
    keys, _ = _Grid(boxes).cells(slice(None))
    assert len(keys) <= CELLS_PER_BOX * len(boxes) + 4096
    q, b = box_pairs(boxes[:-1], boxes)
    assert sorted(zip(q.tolist(), b.tolist(), strict=True)) == brute_pairs(boxes[:-1], boxes)


def test_fusion_at_the_edge_of_the_extent_maps_as_at_the_origin():
    """The same room at the local origin and 9e4 m from it: the same lines, no warning."""
    from scanlines import extract
    from scanlines.geometry.transform import to_world
    from test_map import view

    room = [((-4, -3), (4, -3)), ((4, -3), (4, 3)), ((4, 3), (-4, 3)), ((-4, 3), (-4, -3))]
    maps = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for centre in (0.0, 9e4):
            line_map = LineMap(FusionSettings(min_scans=1))
            for j in range(20):
                scan = view(room, (0.1 * j, 0.05 * j, 0.02 * j), seed=j)
                pose = (centre + 0.1 * j, centre + 0.05 * j, 0.02 * j)
                line_map.add(to_world(extract(scan), pose), j, pose)
            maps.append(line_map.lines())
    near, far = maps
    assert len(far) == len(near) >= 3
    assert far.scans.tolist() == near.scans.tolist()
    # The same walls within a centimetre (a line's normal, and so its start, may point the
    # other way there; the fusion's model noise is added in the frame's (rho, alpha)).
    np.testing.assert_allclose((far.start + far.end) / 2 - 9e4, (near.start + near.end) / 2,
                               atol=0.01)  # fmt: skip
    np.testing.assert_allclose(far.lengths, near.lengths, atol=0.01)
