"""Writers: JSON Lines, CSV, ROS 2 bags with markers, metadata, atomicity, frames."""

from __future__ import annotations

import csv
import json
import math
import os
import stat
from itertools import islice

import numpy as np
import pytest
from io_helpers import make_extraction
from rosbags.highlevel import AnyReader

from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.extraction import Extraction
from scanlines.io import (
    CSV_COLUMNS,
    CsvWriter,
    JsonlWriter,
    Ros2BagWriter,
    meta_path_for,
    open_log,
    open_writer,
    to_world,
)
from scanlines.io.bag_writer import SCAN_FEATURES_TOPIC
from scanlines.outputs import OutputError
from scanlines.scan import Scan


@pytest.fixture(scope="module")
def scans() -> list[Scan]:
    return list(islice(open_log(sample("freiburg")), 4))


def simple_scan(pose=None, timestamp=1.5) -> Scan:
    """Beams at 0 and 90 deg (and a no-return beam in between)."""
    return Scan(
        [2.0, np.nan, 3.0], -0.0, math.pi / 4, timestamp=timestamp, pose=pose, range_max=10.0
    )


def write_all(path, scans, extractions, **kwargs):
    with open_writer(path, **kwargs) as writer:
        for index, (scan, extraction) in enumerate(zip(scans, extractions, strict=True)):
            writer.write(index * 2, scan, extraction)
    return writer


class TestJsonl:
    def test_one_object_per_scan(self, tmp_path, scans) -> None:
        path = tmp_path / "out.jsonl"
        extractions = [
            make_extraction(2),
            make_extraction(0, breakpoints=(), corners=()),
            make_extraction(1),
        ]
        write_all(path, scans[:3], extractions)
        lines = path.read_text().splitlines()
        assert len(lines) == 3
        records = [json.loads(line) for line in lines]
        assert [r["scan"] for r in records] == [0, 2, 4]
        first = records[0]
        assert list(first) == [
            "scan", "timestamp", "pose", "segments", "breakpoints", "corners",
            "breakpoint_xy", "corner_xy",
        ]  # fmt: skip
        assert first["timestamp"] == scans[0].timestamp
        assert first["pose"] == list(scans[0].pose)
        assert first["segments"][1] == {
            "first": 10,
            "last": 19,
            "start": [1.0, 1.0],
            "end": [2.0, 2.0],
            "rho": 2.0,
            "alpha": 0.25,
            "n_points": 10,
            "rms": 0.01,
            "covariance": [[0.0001, 0.0], [0.0, 1e-05]],
            "start_kind": "open",
            "end_kind": "open",
        }
        assert first["breakpoints"] == [9, 30]
        assert first["corners"] == [10]
        assert records[1]["segments"] == []

    def test_missing_values_are_null(self, tmp_path) -> None:
        path = tmp_path / "out.jsonl"
        write_all(path, [simple_scan(timestamp=None)], [make_extraction(1, nan_rms=True)])
        record = json.loads(path.read_text())
        assert record["timestamp"] is None
        assert record["pose"] is None
        assert record["segments"][0]["rms"] is None
        assert "NaN" not in path.read_text()


class TestCsv:
    def test_one_row_per_segment(self, tmp_path, scans) -> None:
        path = tmp_path / "out.csv"
        write_all(
            path,
            scans[:3],
            [make_extraction(2), make_extraction(0), make_extraction(1, nan_rms=True)],
        )
        with path.open() as fh:
            rows = list(csv.reader(fh))
        assert tuple(rows[0]) == CSV_COLUMNS
        assert (
            ",".join(rows[0])
            == "scan,timestamp,first,last,start_x,start_y,end_x,end_y,rho,alpha,n_points,rms,"
            "var_rho,cov_rho_alpha,var_alpha,start_kind,end_kind,"
            "pose_x,pose_y,pose_theta,feature,beam,x,y"
        )
        # segment rows only (then each scan's breakpoints and corners: TestFeaturePoints)
        rows = [row for row in rows[1:] if row[CSV_COLUMNS.index("feature")] == "segment"]
        rows.insert(0, list(CSV_COLUMNS))
        assert len(rows) == 1 + 2 + 0 + 1
        assert rows[1][:17] == [
            "0",
            repr(scans[0].timestamp),
            "0",
            "9",
            "0.0",
            "1.0",
            "1.0",
            "2.0",
            "1.0",
            "0.25",
            "10",
            "0.01",
            "0.0001",
            "0.0",
            "0.00001",  # numbers as in JSON Lines (orjson: shortest round trip, no exponent)
            "open",
            "open",
        ]
        assert [float(v) for v in rows[1][17:20]] == list(scans[0].pose)
        assert rows[1][20:] == ["segment", "", "", ""]
        assert rows[2][:4] == ["0", repr(scans[0].timestamp), "10", "19"]
        assert rows[3][0] == "4"
        assert rows[3][CSV_COLUMNS.index("rms")] == ""  # NaN rms


class TestFeaturePoints:
    """Breakpoints and corners carry their x, y in JSON Lines, CSV and Parquet."""

    @staticmethod
    def expected(scan: Scan, beam: int, pose=None) -> tuple[float, float]:
        angle = scan.angle_min + scan.angle_increment * beam
        x, y = scan.ranges[beam] * math.cos(angle), scan.ranges[beam] * math.sin(angle)
        if pose is None:
            return x, y
        px, py, theta = pose
        c, s = math.cos(theta), math.sin(theta)
        return px + c * x - s * y, py + s * x + c * y

    @pytest.mark.parametrize("frame", ["sensor", "world"])
    def test_jsonl(self, tmp_path, frame) -> None:
        pose = (1.0, 2.0, 0.5)
        scan = simple_scan(pose=pose)
        path = tmp_path / "out.jsonl"
        write_all(path, [scan], [make_extraction(1, breakpoints=(0, 1), corners=(2,))],
                  frame=frame)  # fmt: skip
        record = json.loads(path.read_text())
        world = pose if frame == "world" else None
        assert record["breakpoint_xy"][0] == pytest.approx(self.expected(scan, 0, world))
        assert record["breakpoint_xy"][1] == [None, None]  # beam 1 has no return
        assert record["corner_xy"][0] == pytest.approx(self.expected(scan, 2, world))

    def test_csv_has_breakpoints_corners_and_pose(self, tmp_path) -> None:
        pose = (1.0, 2.0, 0.5)
        scan = simple_scan(pose=pose)
        path = tmp_path / "out.csv"
        write_all(path, [scan], [make_extraction(1, breakpoints=(0, 1), corners=(2,))])
        with path.open() as fh:
            rows = list(csv.DictReader(fh))
        assert [row["feature"] for row in rows] == ["segment", "breakpoint", "breakpoint", "corner"]
        assert all(
            (row["pose_x"], row["pose_y"], row["pose_theta"]) == ("1.0", "2.0", "0.5")
            for row in rows
        )
        corner = rows[3]
        assert corner["beam"] == "2"
        assert (float(corner["x"]), float(corner["y"])) == pytest.approx(self.expected(scan, 2))
        assert corner["first"] == corner["rho"] == corner["end_kind"] == ""
        assert (rows[2]["x"], rows[2]["y"]) == ("", "")

    def test_csv_scan_with_only_a_breakpoint_writes_it(self, tmp_path) -> None:
        path = tmp_path / "out.csv"
        write_all(path, [simple_scan()], [make_extraction(0, breakpoints=(0,), corners=())])
        with path.open() as fh:
            rows = list(csv.DictReader(fh))
        assert [(row["feature"], row["beam"]) for row in rows] == [("breakpoint", "0")]
        assert rows[0]["pose_x"] == ""

    def test_parquet_events(self, tmp_path) -> None:
        pq = pytest.importorskip("pyarrow.parquet")
        from scanlines.extraction import ExtractionTable
        from scanlines.io.parquet import write_parts

        scan = simple_scan()
        extraction = make_extraction(1, breakpoints=(0, 1), corners=(2,))
        table = ExtractionTable.concatenate([extraction], extraction.method, extraction.params)
        write_parts(tmp_path, "log", 0, [7], [scan], table)
        events = pq.read_table(tmp_path / "events" / "log=log").to_pylist()
        assert [(e["kind"], e["beam"]) for e in events] == [
            ("breakpoint", 0), ("breakpoint", 1), ("corner", 2)
        ]  # fmt: skip
        assert (events[0]["x"], events[0]["y"]) == pytest.approx(self.expected(scan, 0))
        assert (events[1]["x"], events[1]["y"]) == (None, None)
        assert (events[2]["x"], events[2]["y"]) == pytest.approx(self.expected(scan, 2))


class TestMeta:
    def test_meta_json_beside_output(self, tmp_path, scans) -> None:
        path = tmp_path / "out.jsonl"
        meta = {"input": "fr079_excerpt.log.gz", "reader": {"format": "carmen", "fov": None}}
        with open_writer(path, meta=meta) as writer:
            for index, scan in enumerate(scans):
                writer.write(index, scan, make_extraction(2))
            writer.update_meta(counts={"skipped_records": 3})
        assert writer.meta_path == meta_path_for(path) == tmp_path / "out.jsonl.meta.json"
        document = json.loads(writer.meta_path.read_text())
        assert document["format_version"] == 1
        assert document["scanlines_version"] == __import__("scanlines").__version__
        assert document["output"] == "out.jsonl"
        assert document["output_format"] == "jsonl"
        assert document["frame"] == "sensor"
        assert document["input"] == "fr079_excerpt.log.gz"
        assert document["reader"] == {"format": "carmen", "fov": None}
        assert document["method"] == "handmade"
        assert document["params"] == {"threshold": 0.05, "window": [1, 2], "max_gap": "inf"}
        assert document["counts"] == {
            "skipped_records": 3,
            "scans": 4,
            "segments": 8,
            "breakpoints": 8,
            "corners": 4,
        }

    def test_caller_method_and_params_win(self, tmp_path) -> None:
        path = tmp_path / "out.csv"
        write_all(
            path, [simple_scan()], [make_extraction(1)], meta={"method": "x", "params": {"a": 1}}
        )
        document = json.loads(meta_path_for(path).read_text())
        assert (document["method"], document["params"]) == ("x", {"a": 1})


def write_then_fail(path, scans, *, frame="sensor", overwrite=False) -> None:
    """Write two scans, then fail: by an exception, or by a scan without pose in world frame."""
    with open_writer(path, frame=frame, overwrite=overwrite) as writer:
        writer.write(0, scans[0], make_extraction(2))
        if frame == "world":
            writer.write(1, simple_scan(pose=None), make_extraction(2))
        writer.write(1, scans[1], make_extraction(3))
        raise RuntimeError("boom")


@pytest.mark.parametrize("suffix", [".jsonl", ".csv", ".mcap", ""])
class TestAtomicity:
    def test_exception_mid_write_leaves_nothing(self, tmp_path, scans, suffix) -> None:
        with pytest.raises(RuntimeError, match="boom"):
            write_then_fail(tmp_path / f"out{suffix}", scans)
        assert list(tmp_path.iterdir()) == []

    def test_failing_write_leaves_nothing(self, tmp_path, scans, suffix) -> None:
        with pytest.raises(ParameterError, match="needs scan poses"):
            write_then_fail(tmp_path / f"out{suffix}", scans, frame="world")
        assert list(tmp_path.iterdir()) == []

    def test_existing_output_kept_until_success(self, tmp_path, scans, suffix) -> None:
        path = tmp_path / f"out{suffix}"
        write_all(path, scans[:1], [make_extraction(1)])
        before = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
        assert len(before) == 2  # the output and its .meta.json
        with pytest.raises(OutputError, match="exists; not replacing it"):
            write_then_fail(path, scans)
        with pytest.raises(RuntimeError):
            write_then_fail(path, scans, overwrite=True)
        assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == before
        write_all(path, scans[:2], [make_extraction(1), make_extraction(1)], overwrite=True)
        assert json.loads(meta_path_for(path).read_text())["counts"]["scans"] == 2


def test_writer_classes_by_suffix(tmp_path) -> None:
    kinds = {
        "a.jsonl": JsonlWriter,
        "a.csv": CsvWriter,
        "a.mcap": Ros2BagWriter,
        "bagdir": Ros2BagWriter,
    }
    for name, cls in kinds.items():
        writer = open_writer(tmp_path / name)
        assert type(writer) is cls
        writer.abort()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ParameterError, match=r"unknown output format '\.xlsx'"):
        open_writer(tmp_path / "a.xlsx")


def read_markers(path):
    """(topic, bag time, message) of every message of a ROS 2 output."""
    with AnyReader([path]) as reader:
        return [
            (connection.topic, time, reader.deserialize(raw, connection.msgtype))
            for connection, time, raw in reader.messages()
        ]


class TestRos2Output:
    @pytest.mark.parametrize(
        ("name", "storage"), [("out.mcap", "mcap"), ("outbag", "sqlite3"), ("outbag", "mcap")]
    )
    def test_scans_read_back_identically(self, tmp_path, scans, name, storage) -> None:
        path = tmp_path / name
        options = {} if name.endswith(".mcap") else {"storage": storage}
        write_all(path, scans, [make_extraction(2)] * 4, **options)
        if not name.endswith(".mcap"):
            assert (path / "metadata.yaml").exists()
            assert next(path.glob("*.db3" if storage == "sqlite3" else "*.mcap"))
        back = list(open_log(path))
        assert len(back) == 4
        for original, scan in zip(scans, back, strict=True):
            np.testing.assert_array_equal(scan.ranges, original.ranges.astype(np.float32))
            assert scan.timestamp == pytest.approx(original.timestamp, abs=1e-9)
            assert scan.range_max == np.float32(80.99)

    def test_markers_in_sensor_frame(self, tmp_path) -> None:
        path = tmp_path / "out.mcap"
        scan = simple_scan(pose=(1.0, 2.0, math.pi / 2))
        extraction = make_extraction(2, breakpoints=(0,), corners=(2,))
        with open_writer(path) as writer:
            writer.write(7, scan, extraction)
            writer.write(
                25, simple_scan(timestamp=None), make_extraction(0, breakpoints=(), corners=())
            )
        messages = read_markers(path)
        topics = [topic for topic, _, _ in messages]
        assert sorted(topics) == sorted(
            ["/scan", "/scanlines/markers", "/tf", "/scan", "/scanlines/markers"]
            + ["/scanlines/features", "/scanlines/scan_features"] * 2
        )
        features = [json.loads(m.data) for t, _, m in messages if t == "/scanlines/features"]
        assert [f["scan"] for f in features] == [7, 25]
        first = features[0]["segments"][0]
        assert first["covariance"] == extraction.covariances[0].tolist()
        assert (first["start_kind"], first["end_kind"]) == ("open", "open")
        arrays = [m for t, _, m in messages if t == "/scanlines/markers"]
        first, second = arrays
        assert [(m.ns, m.type, m.action) for m in first.markers] == [
            ("", 7, 3),  # DELETEALL
            ("segments", 5, 0),  # LINE_LIST
            ("breakpoints", 7, 0),  # SPHERE_LIST
            ("corners", 7, 0),
        ]
        segments, breakpoints, corners = first.markers[1:]
        assert [(p.x, p.y) for p in segments.points] == [
            (0.0, 1.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (2.0, 2.0),
        ]
        assert [(p.x, p.y) for p in breakpoints.points] == [(2.0, 0.0)]
        assert corners.points[0].x == pytest.approx(0.0, abs=1e-12)
        assert corners.points[0].y == pytest.approx(3.0)
        assert {m.header.frame_id for m in first.markers} == {"laser"}
        assert (segments.color.g, breakpoints.color.r, corners.color.b) == pytest.approx(
            (0.8, 0.9, 1.0)
        )
        assert len(second.markers) == 1  # only the DELETEALL
        stamp = second.markers[0].header.stamp
        assert (stamp.sec, stamp.nanosec) == (2, 500_000_000)  # no timestamp: index 25 * 0.1 s
        (tf,) = [m for t, _, m in messages if t == "/tf"]
        transform = tf.transforms[0]
        assert (transform.header.frame_id, transform.child_frame_id) == ("map", "laser")
        assert transform.transform.translation.x == 1.0
        assert transform.transform.rotation.z == pytest.approx(math.sqrt(0.5))

    def test_typed_features_read_back_from_the_definition_in_the_file(self, tmp_path) -> None:
        path = tmp_path / "out.mcap"
        scan = simple_scan(pose=(1.0, 2.0, math.pi / 2))
        extraction = make_extraction(2, breakpoints=(0,), corners=(2,))
        with open_writer(path) as writer:
            writer.write(7, scan, extraction)
        with AnyReader([path]) as reader:  # types from the file's own schema, not ours
            (connection,) = [c for c in reader.connections if c.topic == SCAN_FEATURES_TOPIC]
            assert connection.msgtype == "scanlines/msg/ScanFeatures"
            assert "geometry_msgs/Point[] corner_points" in connection.msgdef.data
            (raw,) = [raw for c, _, raw in reader.messages([connection])]
            typed = reader.deserialize(raw, connection.msgtype)
        assert typed.method == extraction.method
        assert typed.header.frame_id == "laser"
        assert [(s.first, s.last, s.n_points) for s in typed.segments] == [
            (s.first, s.last, s.n_points) for s in extraction.segments
        ]
        np.testing.assert_allclose(
            typed.segments[0].covariance, extraction.covariances[0].ravel(), rtol=1e-6
        )
        assert typed.breakpoints.tolist() == [0]
        assert typed.corners.tolist() == [2]
        assert [(p.x, p.y) for p in typed.breakpoint_points] == [(2.0, 0.0)]
        assert typed.corner_points[0].y == pytest.approx(3.0)

    def test_markers_in_world_frame(self, tmp_path) -> None:
        path = tmp_path / "world"
        scan = simple_scan(pose=(1.0, 2.0, math.pi / 2))
        with open_writer(path, frame="world") as writer:
            writer.write(0, scan, make_extraction(1, breakpoints=(0,), corners=()))
        arrays = [m for t, _, m in read_markers(path) if t == "/scanlines/markers"]
        segments, breakpoints = arrays[0].markers[1:]
        assert segments.header.frame_id == "map"
        got = [(p.x, p.y) for p in segments.points]
        assert got == [pytest.approx((0.0, 2.0)), pytest.approx((-1.0, 3.0))]
        assert (breakpoints.points[0].x, breakpoints.points[0].y) == pytest.approx((1.0, 4.0))


class TestToWorld:
    def test_lines_and_endpoints_consistent(self) -> None:
        rho, alpha = np.array([1.0, 2.0, 0.5]), np.array([0.3, -2.0, 3.0])
        normal, direction = (
            np.column_stack((np.cos(alpha), np.sin(alpha))),
            np.column_stack((-np.sin(alpha), np.cos(alpha))),
        )
        start, end = rho[:, None] * normal - direction, rho[:, None] * normal + 2 * direction
        extraction = Extraction(
            first=[0, 10, 20],
            last=[9, 19, 29],
            n_points=[10, 10, 10],
            lines=np.column_stack((rho, alpha, start, end, [0.01, 0.02, 0.03])),
            covariances=np.tile(np.eye(2), (3, 1, 1)),
            breakpoints=[],
            corners=[],
            outliers=[],
            method="m",
            params={},
        )
        pose = (1.5, -2.0, 2.5)
        moved = to_world(extraction, pose)
        assert isinstance(moved, Extraction)
        rho, alpha = moved.lines[:, 0], moved.lines[:, 1]
        for x_col, y_col in ((2, 3), (4, 5)):
            x, y = moved.lines[:, x_col], moved.lines[:, y_col]
            np.testing.assert_allclose(x * np.cos(alpha) + y * np.sin(alpha), rho, atol=1e-12)
        assert (rho >= 0).all()
        assert ((alpha > -math.pi) & (alpha <= math.pi)).all()
        np.testing.assert_array_equal(moved.first, extraction.first)
        np.testing.assert_array_equal(moved.lines[:, 6], extraction.lines[:, 6])

    def test_known_line(self) -> None:
        # x = 1 in the sensor frame (rho 1, alpha 0); sensor at (0, 3) facing +y: world y = 4.
        line = np.array([[1.0, 0.0, 1.0, -1.0, 1.0, 1.0, 0.0]])
        extraction = Extraction(
            first=[0],
            last=[1],
            n_points=[2],
            lines=line,
            covariances=np.diag([1e-4, 1e-6])[None],
            breakpoints=[],
            corners=[],
            outliers=[],
            method="m",
            params={},
        )
        moved = to_world(extraction, (0.0, 3.0, math.pi / 2))
        rho, alpha, sx, sy, ex, ey, _ = moved.lines[0]
        assert (rho, alpha) == pytest.approx((4.0, math.pi / 2))
        assert (sx, sy, ex, ey) == pytest.approx((1.0, 4.0, -1.0, 4.0))
        # var(rho') = var(rho) + (d rho'/d alpha)^2 var(alpha),
        # with d rho'/d alpha = -x sin(alpha') + y cos(alpha') = 0 here
        assert moved.covariances[0] == pytest.approx(np.diag([1e-4, 1e-6]))

    def test_flip_keeps_rho_positive(self) -> None:
        line = np.array([[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]])
        extraction = Extraction(
            first=[0],
            last=[1],
            n_points=[2],
            lines=line,
            covariances=np.eye(2)[None],
            breakpoints=[],
            corners=[],
            outliers=[],
            method="m",
            params={},
        )
        moved = to_world(extraction, (-3.0, 0.0, 0.0))  # line x = 1 becomes x = -2
        assert moved.lines[0, :2] == pytest.approx((2.0, math.pi))


@pytest.mark.parametrize("suffix", [".jsonl", ".csv", ".mcap"])
def test_outputs_get_the_usual_permissions(tmp_path, suffix) -> None:
    path = tmp_path / f"out{suffix}"
    write_all(path, [simple_scan()], [make_extraction(1)])
    mask = os.umask(0)
    os.umask(mask)
    for produced in (path, meta_path_for(path)):
        assert stat.S_IMODE(produced.stat().st_mode) == 0o666 & ~mask


def test_bag_output_does_not_replace_other_things(tmp_path) -> None:
    plain_file = tmp_path / "results"
    plain_file.write_text("keep me")
    with pytest.raises(ParameterError, match="not a bag directory"):
        open_writer(plain_file, overwrite=True)
    folder = tmp_path / "folder"
    (folder / "sub").mkdir(parents=True)
    with pytest.raises(ParameterError, match="not a ROS 2 bag"):
        open_writer(folder, overwrite=True)
    with pytest.raises(OutputError, match="exists"):
        open_writer(plain_file)
    assert plain_file.read_text() == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder", "results"]
