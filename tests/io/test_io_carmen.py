"""CARMEN reader: real excerpts, options, other message types and malformed records."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.data import sample
from scanlines.errors import LogFormatError, ParameterError
from scanlines.io import CarmenReader, open_log

INTEL_FIRST_RANGES = [2.55, 2.55, 2.50, 2.51, 2.53, 2.55, 2.58, 2.61, 2.63, 2.66]
INTEL_LAST_RANGES = [0.96, 0.96, 0.95, 0.96, 0.96]
FR079_FIRST_RANGES = [1.38, 1.38, 1.38, 1.38, 1.38, 1.37, 1.35, 1.35, 1.34, 1.35]
FR079_LAST_RANGES = [1.21, 1.20, 1.20, 1.19, 1.19]


class TestIntelExcerpt:
    def test_count_and_first_scan(self) -> None:
        reader = open_log(sample("intel"))
        scans = list(reader)
        assert isinstance(reader, CarmenReader)
        assert len(scans) == 300
        first = scans[0]
        assert first.ranges[:10].tolist() == INTEL_FIRST_RANGES
        assert first.ranges[-5:].tolist() == INTEL_LAST_RANGES
        assert len(first) == 180
        assert first.timestamp == 346.569573
        assert first.pose == (0.274, -13.486, 2.083333)
        assert first.angle_min == -math.pi / 2
        assert first.angle_increment == pytest.approx(math.pi / 180, abs=1e-15)
        assert first.angles[-1] == pytest.approx(math.radians(89.0), abs=1e-12)

    def test_no_return_code_is_invalid(self) -> None:
        first = next(iter(open_log(sample("intel"))))
        no_return = first.ranges == 81.83
        assert no_return.sum() == 8
        assert first.range_max == 80.0
        assert not first.valid[no_return].any()
        assert first.valid[~no_return].all()

    def test_counts_of_lines(self) -> None:
        reader = open_log(sample("intel"))
        for _ in reader:
            pass
        assert reader.scan_count == 300
        assert dict(reader.counts) == {"FLASER": 300}
        assert dict(reader.skipped) == {"comment": 6}
        assert reader.info()["message"] == "FLASER"

    def test_timestamps_kept_out_of_order(self) -> None:
        stamps = np.array([s.timestamp for s in open_log(sample("intel"))])
        assert (np.diff(stamps) < 0).any()
        assert stamps[-1] == 405.592779

    def test_linspace_convention(self) -> None:
        first = next(iter(open_log(sample("intel"), angle_convention="linspace")))
        assert first.angles[0] == -math.pi / 2
        assert first.angles[-1] == pytest.approx(math.pi / 2, abs=1e-12)

    def test_fov_option(self) -> None:
        first = next(iter(open_log(sample("intel"), fov=90.0)))
        assert first.angle_min == pytest.approx(-math.pi / 4)
        assert first.angle_increment == pytest.approx(math.radians(0.5))

    def test_iterating_twice_gives_the_same_scans(self) -> None:
        reader = open_log(sample("intel"))
        once = [s.ranges for s in reader]
        twice = [s.ranges for s in reader]
        assert len(once) == len(twice) == 300
        assert all(np.array_equal(a, b) for a, b in zip(once, twice, strict=True))
        assert reader.counts["FLASER"] == 300


class TestFreiburgExcerpt:
    def test_count_and_first_scan(self) -> None:
        reader = open_log(sample("freiburg"))
        scans = list(reader)
        assert len(scans) == 300
        first = scans[0]
        assert len(first) == 360
        assert first.ranges[:10].tolist() == FR079_FIRST_RANGES
        assert first.ranges[-5:].tolist() == FR079_LAST_RANGES
        assert first.timestamp == 130.452466
        assert first.pose == (-6.180116, 7.458431, 2.572913)
        assert first.angle_increment == pytest.approx(math.radians(0.5), abs=1e-15)
        assert first.angles[-1] == pytest.approx(math.radians(89.5), abs=1e-12)

    def test_max_range_from_param(self) -> None:
        reader = open_log(sample("freiburg"))
        first = next(iter(reader))
        assert first.range_max == 80.99
        assert reader.params["robot_front_laser_max"] == "80.99"
        assert reader.params["laser_front_laser_resolution"] == "0.5"
        assert (first.ranges == 81.91).sum() == 2
        assert first.valid.sum() == 358

    def test_max_range_option_overrides_param(self) -> None:
        first = next(iter(open_log(sample("freiburg"), max_range=1.3)))
        assert first.range_max == 1.3
        assert not first.valid[:10].any()

    def test_robot_pose_and_ipc_timestamp(self) -> None:
        first = next(iter(open_log(sample("freiburg"), pose="robot", timestamp="ipc")))
        assert first.pose == (-6.213820, 7.479971, 2.572913)
        assert first.timestamp == 381.659356

    def test_other_lines_counted(self) -> None:
        reader = open_log(sample("freiburg"))
        assert sum(1 for _ in reader) == 300
        assert reader.counts == {"FLASER": 300, "ODOM": 560, "PARAM": 180}
        assert reader.skipped == {"comment": 12}


def test_corrected_intel_log_with_odom_neff_param(fixtures) -> None:
    reader = open_log(fixtures / "intel_corrected_head.log.gz")
    scans = list(reader)
    assert len(scans) == 5
    assert reader.counts == {"PARAM": 2, "ODOM": 221, "FLASER": 5}
    assert reader.skipped == {"comment": 2, "NEFF": 5}
    first = scans[0]
    assert first.ranges[:5].tolist() == [1.09, 1.08, 1.08, 1.07, 1.06]
    assert first.ranges[-3:].tolist() == [1.24, 1.22, 1.23]
    assert first.pose == (0.600266, -0.0320327, -0.354665)
    assert first.timestamp == 32.9068
    assert reader.params == {"robot_frontlaser_offset": "0.0", "robot_rearlaser_offset": "0.0"}


class TestNewLaserMessages:
    def test_robotlaser_preferred_and_parsed(self, fixtures) -> None:
        reader = open_log(fixtures / "carmen_new_formats.log")
        scans = list(reader)
        assert reader.message == "ROBOTLASER1"
        assert len(scans) == 2
        first = scans[0]
        assert first.angles.tolist() == [-1.5, -0.5, 0.5, 1.5]
        assert first.ranges[:3].tolist() == [1.0, 2.0, 25.0]
        assert math.isnan(first.ranges[3])
        assert first.range_max == 20.0
        assert first.valid.tolist() == [True, True, False, False]
        assert first.intensities.tolist() == [10.0, 20.0, 30.0, 40.0]
        assert first.pose == (1.1, 2.1, 0.6)  # the laser pose
        assert first.timestamp == 2.2
        assert scans[1].intensities is None
        assert scans[1].pose == (1.6, 2.6, 0.8)

    def test_skipped_per_type(self, fixtures) -> None:
        reader = open_log(fixtures / "carmen_new_formats.log")
        list(reader)
        assert reader.counts == {"PARAM": 2, "ODOM": 2, "ROBOTLASER1": 2}
        assert reader.skipped == {
            "comment": 1,
            "blank": 1,
            "SYNC": 1,
            "RAWLASER1": 2,
            "TRUEPOS": 1,
            "NEFF": 1,
            "VERTEX_SE2": 1,
            "EDGE_SE2": 1,
            "FLASER": 1,
        }

    def test_robot_pose_option(self, fixtures) -> None:
        first = next(iter(open_log(fixtures / "carmen_new_formats.log", pose="robot")))
        assert first.pose == (1.0, 2.0, 0.5)

    def test_rawlaser_takes_latest_odometry_pose(self, fixtures) -> None:
        scans = list(open_log(fixtures / "carmen_new_formats.log", message="RAWLASER1"))
        assert [s.pose for s in scans] == [(1.0, 2.0, 0.5), (1.5, 2.5, 0.7)]
        assert [s.timestamp for s in scans] == [2.1, 2.5]
        assert scans[1].valid.tolist() == [True, True, False, False]  # 0.0 and inf

    def test_flaser_fov_from_param(self, fixtures) -> None:
        scans = list(open_log(fixtures / "carmen_new_formats.log", message="FLASER"))
        assert len(scans) == 1
        assert scans[0].angle_min == pytest.approx(math.radians(-50.0))
        assert scans[0].angle_increment == pytest.approx(math.radians(100.0 / 3))
        assert scans[0].range_max == 80.99


class TestMalformedRecords:
    def test_wrong_field_count(self, fixtures) -> None:
        path = fixtures / "carmen_wrong_field_count.log"
        with pytest.raises(LogFormatError) as caught:
            list(open_log(path))
        error = caught.value
        assert (error.path, error.record, error.field) == (str(path), 3, "ipc_hostname")
        assert str(error).startswith(f"{path}, line 3, field ipc_hostname: ODOM has 8 fields")

    def test_not_a_number(self, fixtures) -> None:
        path = fixtures / "carmen_not_a_number.log"
        reader = open_log(path)
        scans = reader.enumerate()
        assert next(scans)[0] == 0  # the good record comes out before the error
        with pytest.raises(LogFormatError, match=r"line 3, field range\[2\]: not a number: '1.2O'"):
            next(scans)

    def test_count_mismatch(self, fixtures) -> None:
        path = fixtures / "carmen_count_mismatch.log"
        with pytest.raises(LogFormatError) as caught:
            list(open_log(path))
        assert (caught.value.record, caught.value.field) == (4, "num_readings")
        assert "num_readings = 6, so the record has 17 fields, but it has 16" in str(caught.value)

    def test_skip_mode_counts_and_keeps_messages(self, fixtures) -> None:
        reader = open_log(fixtures / "carmen_malformed_mixed.log", on_error="skip")
        indexed = list(reader.enumerate())
        assert [index for index, _ in indexed] == [0, 2, 4]  # record numbers of the good ones
        assert [scan.ranges[0] for _, scan in indexed] == [1.0, 2.0, 3.0]
        assert reader.error_count == 4
        assert [e.split(": ", 1)[0] for e in reader.errors] == [
            f"{fixtures / 'carmen_malformed_mixed.log'}, line {n}, field {f}"
            for n, f in [
                (4, "num_readings"),
                (6, "range[2]"),
                (7, "ipc_hostname"),
                (9, "param_value"),
            ]
        ]
        assert reader.counts == {"FLASER": 3, "PARAM": 1}
        assert indexed[0][1].range_max == 50.0

    def test_fail_mode_stops_at_first_bad_record(self, fixtures) -> None:
        reader = open_log(fixtures / "carmen_malformed_mixed.log")
        scans = reader.enumerate()
        assert next(scans)[0] == 0
        with pytest.raises(LogFormatError, match="line 4"):
            next(scans)

    def test_nonfinite_pose_names_the_field(self, tmp_path) -> None:
        path = tmp_path / "x.log"
        path.write_text("FLASER 2 1.0 1.0 nan 0 0 0 0 0 1.0 host 1.0\n")
        with pytest.raises(LogFormatError) as caught:
            list(open_log(path))
        assert (caught.value.record, caught.value.field) == (1, "pose[0]")

    def test_log_without_laser_records(self, tmp_path) -> None:
        path = tmp_path / "odom_only.log"
        path.write_text("ODOM 0 0 0 0 0 0 1.0 host 1.0\n")
        with pytest.raises(LogFormatError, match="no laser records"):
            list(open_log(path))


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("angle_convention", "middle"),
        ("message", "LASER5"),
        ("fov", 0.0),
        ("max_range", -1.0),
        ("on_error", "ignore"),
        ("pose", "odom"),
    ],
)
def test_bad_options_are_rejected(option, value) -> None:
    with pytest.raises(ParameterError, match=option):
        open_log(sample("intel"), **{option: value})


def test_lines_without_a_message_name_count_as_other(tmp_path) -> None:
    path = tmp_path / "junk.log"
    lines = ["FLASER 2 1.0 2.0 0 0 0 0 0 0 1.0 host 1.0"] + [f"junk{i} 1 2" for i in range(50)]
    path.write_text("\n".join([*lines, "12 34", "VERTEX_SE2 1 0 0 0"]) + "\n")
    reader = open_log(path)
    assert len(list(reader)) == 1
    assert reader.skipped == {"other": 51, "VERTEX_SE2": 1}
