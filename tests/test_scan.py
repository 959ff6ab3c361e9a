"""The Scan type: validation, immutability, derived arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from scanlines import Scan, ScanError
from scanlines.extractor import float32
from scanlines.scan import valid_returns

any_float = st.floats(allow_nan=True, allow_infinity=True)


def test_valid_mask_treats_no_return_as_data():
    ranges = [1.0, 0.0, -1.0, math.inf, math.nan, 0.05, 35.0, 2.0]
    scan = Scan(ranges, 0.0, 0.1, range_min=0.1, range_max=30.0)
    assert scan.valid.tolist() == [True, False, False, False, False, False, False, True]
    assert np.isnan(scan.points[1]).all()
    assert scan.points[0].tolist() == [1.0, 0.0]


@given(st.lists(any_float, max_size=20), any_float, any_float)
@example([1.0, math.inf, 0.0], math.nan, 5.0)
@example([1.0, math.inf, 0.0], 0.0, math.nan)
@example([1.0, math.inf, 0.0], math.inf, math.inf)
def test_valid_returns_is_the_rule_as_written(ranges, range_min, range_max):
    ranges = np.array(ranges, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        rule = np.isfinite(ranges) & (ranges > 0) & (ranges >= range_min) & (ranges <= range_max)
    assert valid_returns(ranges, range_min, range_max).tolist() == rule.tolist()


@given(any_float)
def test_float32_rounds_as_numpy_does(value):
    with np.errstate(over="ignore"):
        expected = float(np.float32(value))
    got = float32(value)
    assert (math.isnan(got) and math.isnan(expected)) or (
        got == expected and math.copysign(1, got) == math.copysign(1, expected)
    )


def test_points_follow_rep_103():
    scan = Scan([1.0, 1.0], -math.pi / 2, math.pi / 2)
    np.testing.assert_allclose(scan.points, [[0.0, -1.0], [1.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(scan.angles, [-math.pi / 2, 0.0])


def test_input_is_copied_and_scan_is_immutable():
    ranges = np.array([1.0, 2.0, 3.0])
    scan = Scan(ranges, 0.0, 0.1)
    ranges[0] = 99.0
    assert scan.ranges[0] == 1.0
    with pytest.raises(ValueError, match="read-only"):
        scan.ranges[0] = 5.0
    with pytest.raises(AttributeError):
        scan.angle_min = 1.0


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"ranges": [[1.0, 2.0]]}, "ranges"),
        ({"ranges": ["a", "b"]}, "ranges"),
        ({"ranges": [1.0, 2.0], "angle_increment": 0.0}, "angle_increment"),
        ({"ranges": [1.0, 2.0], "angle_increment": math.nan}, "angle_increment"),
        ({"ranges": [1.0, 2.0], "angle_increment": math.inf}, "angle_increment"),
        ({"ranges": [1.0, 2.0], "angle_min": "x"}, "angle_min"),
        ({"ranges": [1.0, 2.0], "intensities": [1.0]}, "intensities"),
        ({"ranges": [1.0, 2.0], "pose": (1.0, 2.0)}, "pose"),
        ({"ranges": [1.0, 2.0], "range_min": 5.0, "range_max": 1.0}, "range_min"),
        ({"ranges": [1.0, 2.0], "timestamp": "noon"}, "timestamp"),
    ],
)
def test_invalid_construction_names_the_field(kwargs, field):
    arguments = {"angle_min": 0.0, "angle_increment": 0.1, **kwargs}
    with pytest.raises(ScanError, match=field) as info:
        Scan(**arguments)
    assert isinstance(info.value, ValueError)


def test_full_circle_rule():
    step = 2 * math.pi / 360
    assert Scan(np.ones(360), 0.0, step).full_circle
    # The seam gap may be up to one and a half increments.
    assert Scan(np.ones(360), 0.0, 2 * math.pi / 360.4).full_circle
    assert not Scan(np.ones(359), 0.0, step).full_circle
    assert Scan(np.ones(360), 0.0, -step).full_circle


def test_optional_fields_are_kept():
    scan = Scan([1.0, 2.0], 0.0, 0.1, timestamp=12.5, intensities=[3, 4], pose=(1, 2, 0.5))
    assert scan.timestamp == 12.5
    assert scan.intensities.tolist() == [3.0, 4.0]
    assert scan.pose == (1.0, 2.0, 0.5)
    assert len(scan) == 2


def test_scan_pickles_for_worker_processes():
    import pickle

    scan = Scan([1.0, math.nan, 2.0], -0.5, 0.25, range_max=30.0, timestamp=3.0, pose=(1, 2, 3))
    copy = pickle.loads(pickle.dumps(scan))
    assert np.array_equal(copy.ranges, scan.ranges, equal_nan=True)
    assert (copy.angle_min, copy.angle_increment, copy.range_max) == (-0.5, 0.25, 30.0)
    assert copy.pose == scan.pose
    assert copy.valid.tolist() == [True, False, True]
