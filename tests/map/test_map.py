"""Line maps (scanlines.map, ``scanlines map``, ``scanlines eval --map``): association and
fusion on synthetic walls, the writers read back by independent readers, poses files,
the commands on the shipped sample logs."""

from __future__ import annotations

import itertools
import json
import math
import shutil
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from scanlines import Scan, extract
from scanlines.cli.commands import app
from scanlines.data import sample
from scanlines.geometry.transform import to_world
from scanlines.map import FusionSettings, LineMap, build_map
from scanlines.map.export import write_map
from scanlines.map.holdout import loop_lines
from scanlines.map.poses import PoseError, read_tum, write_tum
from scenes import cast

STEP = math.radians(0.5)


def view(walls, pose, *, sigma=0.005, seed=0, fov_deg=270.0, range_max=8.0, t=None) -> Scan:
    """The scan a sensor at ``pose`` (world) takes of world ``walls``, with range noise."""
    x, y, theta = pose
    n = round(fov_deg / 0.5) + 1
    angles = -math.radians(fov_deg) / 2 + STEP * np.arange(n)
    # cast() shoots from the origin: the walls moved by the sensor's offset, bearings turned
    shifted = [((a[0] - x, a[1] - y), (b[0] - x, b[1] - y)) for a, b in walls]
    ranges = cast(shifted, angles + theta)
    ranges = ranges + np.random.default_rng(seed).normal(0.0, sigma, n)
    ranges = np.where(ranges > range_max, np.inf, ranges)
    return Scan(ranges, -math.radians(fov_deg) / 2, STEP, timestamp=t, pose=pose)


def fused(line_map: LineMap, scan: Scan, index: int) -> None:
    line_map.add(to_world(extract(scan), scan.pose), index, scan.pose)


WALL = [((-3.0, 2.0), (6.0, 2.0))]


def test_two_noisy_views_of_one_wall_fuse_into_one_line_known_better_than_either():
    a = view(WALL, (0.0, 0.0, 0.3), seed=1)
    b = view(WALL, (2.5, -0.5, -0.2), seed=2)
    alone = []
    for scan in (a, b):
        one = LineMap(FusionSettings(min_scans=1))
        fused(one, scan, 0)
        alone.append(one.lines())
        assert len(alone[-1]) == 1
    both = LineMap(FusionSettings(min_scans=1))
    fused(both, a, 0)
    fused(both, b, 1)
    lines = both.lines()
    assert len(lines) == 1
    assert lines.scans[0] == 2
    assert lines.segments[0] == 2
    assert (lines.first_scan[0], lines.last_scan[0]) == (0, 1)
    for single in alone:
        assert lines.covariances[0, 0, 0] < single.covariances[0, 0, 0]
        assert lines.covariances[0, 1, 1] < single.covariances[0, 1, 1]
        assert np.linalg.det(lines.covariances[0]) < np.linalg.det(single.covariances[0])
    assert lines.rho[0] == pytest.approx(2.0, abs=0.02)
    assert lines.alpha[0] == pytest.approx(math.pi / 2, abs=0.01)
    # The extent grows with what supports it: both views' reach along the wall.
    assert lines.lengths[0] > max(single.lengths[0] for single in alone)


def test_a_line_seen_by_fewer_than_min_scans_scans_is_dropped_as_clutter():
    room = [((-4, -3), (4, -3)), ((4, -3), (4, 3)), ((4, 3), (-4, 3)), ((-4, 3), (-4, -3))]
    box = [((1.0, 0.5), (1.0, 1.5))]  # there in one scan only: someone standing by
    line_map = LineMap(FusionSettings(min_scans=3))
    for k in range(5):
        walls = room + box if k == 2 else room
        fused(line_map, view(walls, (-1.0 + 0.2 * k, 0.1 * k, 0.05 * k), seed=k), k)
    kept = line_map.lines()
    everything = line_map.lines(min_scans=1)
    near_box = np.abs(everything.rho - 1.0) < 0.05
    assert near_box.any()  # the clutter was a line ...
    assert not (np.abs(kept.rho - 1.0) < 0.05).any()  # ... and is not in the map
    assert len(kept) == 3
    assert (kept.scans >= 3).all()


RING_OUTER = [((-10, -10), (10, -10)), ((10, -10), (10, 10)), ((10, 10), (-10, 10)),
              ((-10, 10), (-10, -10))]  # fmt: skip
RING_INNER = [((-8, -8), (8, -8)), ((8, -8), (8, 8)), ((8, 8), (-8, 8)), ((-8, 8), (-8, -8))]


def ring_poses(step: float = 0.5):
    """A loop along the middle of a 2 m wide square ring corridor, back to its start."""
    corners = [(-9.0, -9.0), (9.0, -9.0), (9.0, 9.0), (-9.0, 9.0), (-9.0, -9.0)]
    poses = []
    for (x0, y0), (x1, y1) in itertools.pairwise(corners):
        heading = math.atan2(y1 - y0, x1 - x0)
        n = round(math.hypot(x1 - x0, y1 - y0) / step)
        poses += [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, heading) for k in range(n)]
    return [*poses, poses[0]]


def test_loop_a_wall_seen_at_the_start_and_at_the_end_is_one_line():
    walls = RING_OUTER + RING_INNER
    poses = ring_poses()
    scans = [(k, view(walls, pose, seed=k)) for k, pose in enumerate(poses)]
    build = build_map(scans)
    lines = build.line_map.lines()
    assert loop_lines(lines, 0, build.last_index) >= 2  # the start's walls, seen again
    # Eight walls; none mapped twice side by side.
    assert 8 <= len(lines) <= 12
    rho, _ = lines.world_hesse()
    for wall_rho in (8.0, 10.0):
        assert (np.abs(rho - wall_rho) < 0.05).sum() >= 4


def test_the_maps_state_does_not_grow_with_repeated_scans_of_the_same_walls():
    room = [((-4, -3), (4, -3)), ((4, -3), (4, 3)), ((4, 3), (-4, 3)), ((-4, 3), (-4, -3))]
    line_map = LineMap()
    sizes = []
    for k in range(240):
        pose = (0.5 * math.cos(k / 10), 0.5 * math.sin(k / 10), k / 40)
        fused(line_map, view(room, pose, seed=k), k)
        if k % 60 == 59:
            sizes.append((len(line_map), line_map._rho.nbytes))
    assert sizes[-1] == sizes[1]  # lines and storage the same after 120 and 240 scans
    assert len(line_map.lines()) == 4


def small_map():
    line_map = LineMap(FusionSettings(min_scans=1))
    room = [((-4, -3), (4, -3)), ((4, -3), (4, 3)), ((4, 3), (-4, 3))]
    for k in range(3):
        fused(line_map, view(room, (0.1 * k, 0.0, 0.0), seed=k), k)
    return line_map.lines()


def test_geojson_is_read_back_by_shapely(tmp_path):
    shapely_geometry = pytest.importorskip("shapely.geometry")
    lines = small_map()
    path = write_map(lines, tmp_path / "map.geojson", overwrite=False)
    document = json.loads(path.read_text())
    assert document["type"] == "FeatureCollection"
    shapes = [shapely_geometry.shape(f["geometry"]) for f in document["features"]]
    assert len(shapes) == len(lines) == 3
    assert all(s.geom_type == "LineString" and s.is_valid for s in shapes)
    assert sum(s.length for s in shapes) == pytest.approx(float(lines.lengths.sum()))
    assert {"covariance", "scans", "first_scan"} <= document["features"][0]["properties"].keys()


def test_dxf_is_read_back_by_ezdxf(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    lines = small_map()
    path = write_map(lines, tmp_path / "map.dxf", meta={"log": "room"}, overwrite=False)
    entities = list(ezdxf.readfile(path).modelspace().query("LINE"))
    assert len(entities) == len(lines)
    starts = sorted(tuple(round(v, 6) for v in e.dxf.start)[:2] for e in entities)
    assert starts == sorted(tuple(round(float(v), 6) for v in s) for s in lines.start)
    auditor = ezdxf.readfile(path).audit()
    assert not auditor.has_errors


def test_svg_parses_as_xml_and_renders_where_rsvg_is_installed(tmp_path):
    lines = small_map()
    path = write_map(lines, tmp_path / "map.svg", meta={"log": "a <room>"}, overwrite=False)
    root = ET.parse(path).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert len(root.findall(".//{http://www.w3.org/2000/svg}line")) == len(lines)
    if shutil.which("rsvg-convert"):
        png = tmp_path / "map.png"
        subprocess.run(["rsvg-convert", str(path), "-o", str(png)], check=True)
        assert png.stat().st_size > 0


def test_json_keeps_the_covariances(tmp_path):
    lines = small_map()
    path = write_map(lines, tmp_path / "map.json", overwrite=False)
    records = json.loads(path.read_text())["lines"]
    assert len(records) == len(lines)
    np.testing.assert_allclose([r["covariance"] for r in records], lines.covariances)
    np.testing.assert_allclose([r["rho"] for r in records], lines.rho)
    assert [r["scans"] for r in records] == lines.scans.tolist()
    with pytest.raises(Exception, match="exists"):
        write_map(lines, path, overwrite=False)


def test_a_bad_tum_line_is_named_with_its_file_and_line(tmp_path):
    path = tmp_path / "poses.tum"
    path.write_text("# timestamp tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n1 2 3 0 0 zero 0 1\n")
    with pytest.raises(PoseError, match=r"poses\.tum: line 3: .*not a number"):
        read_tum(path)
    path.write_text("0 0 0 0 0 0 0 1\n1 2 3 0 0 0 1\n")
    with pytest.raises(PoseError, match=r"poses\.tum: line 2: a TUM pose has 8 fields"):
        read_tum(path)
    path.write_text("0 0 0 0 0 0 0 nan\n")
    with pytest.raises(PoseError, match=r"line 1: field qw is not finite"):
        read_tum(path)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.floats(-50, 50), st.floats(-50, 50), st.floats(-math.pi + 1e-3, math.pi - 1e-3)
        ),
        min_size=2,
        max_size=6,
    )
)
def test_tum_poses_round_trip_and_interpolate(tmp_path_factory, poses):
    path = tmp_path_factory.mktemp("tum") / "trajectory.tum"
    write_tum(path, [(float(k), pose) for k, pose in enumerate(poses)])
    trajectory = read_tum(path)
    for k, (x, y, theta) in enumerate(poses):
        got = trajectory(0, Scan([1.0], 0.0, 0.1, timestamp=float(k)))
        assert got[0] == pytest.approx(x, abs=1e-5)
        assert got[1] == pytest.approx(y, abs=1e-5)
        assert math.remainder(got[2] - theta, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)
    assert trajectory(0, Scan([1.0], 0.0, 0.1, timestamp=len(poses) + 5.0)) is None


def test_map_command_writes_each_format_and_refuses_what_it_cannot(tmp_path):
    log = str(sample("intel"))
    runner = CliRunner()
    out = tmp_path / "intel.geojson"
    done = runner.invoke(app, ["map", log, "--out", str(out), "--scans", "120"])
    assert done.exit_code == 0, done.output
    assert "map lines from" in done.output
    assert "the log's poses" in done.output
    features = json.loads(out.read_text())["features"]
    assert len(features) > 10
    again = runner.invoke(app, ["map", log, "--out", str(out), "--scans", "120"])
    assert again.exit_code == 2
    assert "exists" in again.output
    fewer = runner.invoke(
        app, ["map", log, "--out", str(out), "--scans", "120", "--min-scans", "20", "--overwrite"]
    )
    assert fewer.exit_code == 0, fewer.output
    assert len(json.loads(out.read_text())["features"]) < len(features)
    unknown = runner.invoke(app, ["map", str(sample("intel")), "--out", "map.txt"])
    assert unknown.exit_code == 2
    assert "map.txt: a map is written as .geojson" in unknown.output  # before the log is read


def test_map_command_without_poses_uses_registration_and_says_so(tmp_path):
    out = tmp_path / "urg.svg"
    done = CliRunner().invoke(app, ["map", str(sample("urg")), "--out", str(out), "--scans", "40"])
    assert done.exit_code == 0, done.output
    assert "carries none; scan registration" in done.output
    ET.parse(out)


def test_map_command_with_a_tum_file(tmp_path):
    from scanlines.io import open_log

    with open_log(sample("intel")) as reader:
        stamped = [(s.timestamp, s.pose) for _, s in zip(range(60), reader, strict=False)]
    tum = tmp_path / "intel.tum"
    write_tum(tum, stamped)
    out = tmp_path / "intel.json"
    args = ["map", str(sample("intel")), "--out", str(out), "--scans", "60", "--poses", str(tum)]
    done = CliRunner().invoke(app, args)
    assert done.exit_code == 0, done.output
    assert "the trajectory intel.tum" in done.output
    assert json.loads(out.read_text())["lines"]


def test_eval_map_prints_and_writes_the_held_out_score(tmp_path):
    done = CliRunner().invoke(
        app, ["eval", "map", str(sample("intel")), "--scans", "200", "--out", str(tmp_path)]
    )
    assert done.exit_code == 0, done.output
    assert "coverage" in done.output
    assert "loop" in done.output
    score = json.loads((tmp_path / "map_eval.json").read_text())
    assert score["held_out_scans"] == 20
    assert score["mapped_scans"] == 180
    assert 0.5 < score["coverage"] <= 1.0
    assert 0 < score["median_distance"] < 0.05
    assert score["lines"] > 0
    assert score["segments_per_line"] > 1
