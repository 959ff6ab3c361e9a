"""CSV and NPZ readers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.errors import LogFormatError, ParameterError
from scanlines.io import CsvReader, NpzReader, open_log

NPZ_FIXTURE = "intel_every5th_rows1098-1109.npz"


class TestCsv:
    def test_ragged_fixture_geometry_header_and_error(self, fixtures) -> None:
        path = fixtures / "table_ragged.csv"
        reader = open_log(path)
        assert isinstance(reader, CsvReader)
        assert reader.timestamp_column
        assert (reader.angle_min, reader.angle_increment, reader.range_max) == (-1.0, 0.5, 10.0)
        rows = reader.enumerate()
        index, first = next(rows)
        assert index == 0
        assert first.ranges.tolist() == [1.0, 1.1, 1.2, 1.3, 1.4]
        assert first.timestamp == 0.0
        assert first.angles.tolist() == [-1.0, -0.5, 0.0, 0.5, 1.0]
        second = next(rows)[1]
        assert second.valid.tolist() == [True, True, False, True, False]  # empty cell and nan
        with pytest.raises(LogFormatError) as caught:
            next(rows)
        assert (caught.value.record, caught.value.field) == (5, "ranges")
        assert "row has 5 values, the first row has 6" in str(caught.value)

    def test_options_override_comments(self, fixtures) -> None:
        reader = open_log(fixtures / "table_ragged.csv", angle_min=0.0, on_error="skip")
        scans = list(reader)
        assert len(scans) == 2
        assert reader.error_count == 1
        assert scans[0].angle_min == 0.0
        assert reader.skipped == {"comment": 1, "header": 1}

    def test_whitespace_separated_without_header(self, tmp_path) -> None:
        path = tmp_path / "scans.csv"
        path.write_text("# plain ranges\n1 2 3\n4 inf 6\n")
        scans = list(open_log(path, angle_min=-0.1, angle_increment=0.1, range_max=5.0))
        assert [s.ranges.tolist() for s in scans] == [[1.0, 2.0, 3.0], [4.0, math.inf, 6.0]]
        assert [s.timestamp for s in scans] == [None, None]
        assert scans[1].valid.tolist() == [True, False, False]

    def test_non_number_names_the_column(self, tmp_path) -> None:
        path = tmp_path / "scans.csv"
        path.write_text("time,a,b\n0.5,1.0,oops\n")
        with pytest.raises(LogFormatError, match=r"line 2, field range\[1\]: not a number"):
            list(open_log(path, angle_min=0.0, angle_increment=0.1))

    def test_angles_are_required(self, tmp_path) -> None:
        path = tmp_path / "scans.csv"
        path.write_text("1,2,3\n")
        with pytest.raises(ParameterError, match="angle_min and angle_increment"):
            open_log(path)


class TestNpz:
    def test_shared_layout_first_scan(self, fixtures) -> None:
        source = np.load(fixtures / NPZ_FIXTURE)
        reader = open_log(fixtures / NPZ_FIXTURE)
        assert isinstance(reader, NpzReader)
        scans = list(reader)
        assert len(scans) == 12
        first = scans[0]
        expected = np.where(source["valid"][0] != 0, source["ranges"][0].astype(float), np.nan)
        np.testing.assert_array_equal(first.ranges, expected)
        assert np.isnan(first.ranges[0])  # 81.83 with valid == 0
        assert first.ranges[4] == np.float32(3.64)
        assert first.valid.sum() == (source["valid"][0] != 0).sum() == 155
        assert first.timestamp == 1084.309574
        assert first.pose == tuple(source["odom_pose"][0].tolist())
        assert first.angle_min == -math.pi / 2
        assert first.angle_increment == math.pi / 180

    def test_nan_timestamps_become_none(self, fixtures) -> None:
        stamps = [s.timestamp for s in open_log(fixtures / NPZ_FIXTURE)]
        assert stamps[:4] == [1084.309574, 1085.609305, 1086.325417, 1087.193208]
        assert stamps[4:] == [None] * 8

    def test_info_without_reading(self, fixtures) -> None:
        info = open_log(fixtures / NPZ_FIXTURE).info()
        assert (info["scans_in_file"], info["beams"]) == (12, 180)
        assert info["keys"] == [
            "ranges",
            "valid",
            "angle_min",
            "angle_increment",
            "timestamp",
            "odom_pose",
        ]
        assert info["ignored_keys"] == ["odom_increment", "orig_index_inferred", "sot_index"]

    def test_generic_layout_per_scan_angles_and_poses(self, tmp_path) -> None:
        path = tmp_path / "stack.npz"
        ranges = np.arange(12, dtype=float).reshape(3, 4) + 1
        np.savez(
            path,
            ranges=ranges,
            angle_min=np.array([-1.0, -2.0, -3.0]),
            angle_increment=0.5,
            range_max=10.0,
            timestamps=np.array([3.0, 1.0, 2.0]),
            poses=np.array([[0, 0, 0], [1, 1, 1], [np.nan, 0, 0]], dtype=float),
        )
        scans = list(open_log(path))
        assert [s.angle_min for s in scans] == [-1.0, -2.0, -3.0]
        assert [s.timestamp for s in scans] == [3.0, 1.0, 2.0]
        assert [s.pose for s in scans] == [(0.0, 0.0, 0.0), (1.0, 1.0, 1.0), None]
        assert np.array_equal(np.stack([s.ranges for s in scans]), ranges)
        assert scans[0].range_max == 10.0

    def test_single_scan(self, tmp_path) -> None:
        path = tmp_path / "one.npz"
        np.savez(path, ranges=[1.0, 2.0], angle_min=0.0, angle_increment=0.1, pose=[1, 2, 3])
        (scan,) = list(open_log(path))
        assert scan.ranges.tolist() == [1.0, 2.0]
        assert scan.pose == (1.0, 2.0, 3.0)

    def test_fortran_order_rows(self, tmp_path) -> None:
        path = tmp_path / "fortran.npz"
        ranges = np.asfortranarray(np.arange(6, dtype=float).reshape(2, 3))
        np.savez(path, ranges=ranges, angle_min=0.0, angle_increment=0.1)
        assert [s.ranges.tolist() for s in open_log(path)] == [[0, 1, 2], [3, 4, 5]]

    @pytest.mark.parametrize(
        ("arrays", "field", "message"),
        [
            ({"angle_min": 0.0, "angle_increment": 0.1}, "ranges", "no 'ranges' array"),
            ({"ranges": np.ones((2, 3)), "angle_min": 0.0}, "angle_increment", "missing"),
            (
                {
                    "ranges": np.ones((2, 3)),
                    "angle_min": 0.0,
                    "angle_increment": 0.1,
                    "poses": np.ones((2, 2)),
                },
                "poses",
                "does not fit",
            ),
        ],
    )
    def test_layout_errors(self, tmp_path, arrays, field, message) -> None:
        path = tmp_path / "bad.npz"
        np.savez(path, **arrays)
        with pytest.raises(LogFormatError, match=message) as caught:
            open_log(path)
        assert caught.value.field == field

    def test_bad_row_skipped(self, tmp_path) -> None:
        path = tmp_path / "zero.npz"
        np.savez(path, ranges=np.ones((3, 2)), angle_min=0.0, angle_increment=[0.1, 0.0, 0.1])
        reader = open_log(path, on_error="skip")
        assert [i for i, _ in reader.enumerate()] == [0, 2]
        assert reader.error_count == 1
        assert "scan 1: angle_increment must be non-zero" in reader.errors[0]
