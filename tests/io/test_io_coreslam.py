"""CoreSLAM .dat reader on the first 30 lines of BreezySLAM's exp1.dat."""

from __future__ import annotations

import gzip
import math

import numpy as np
import pytest

from scanlines.errors import LogFormatError
from scanlines.io import CoreSlamReader, open_log


def test_count_and_first_scan(fixtures) -> None:
    reader = open_log(fixtures / "exp1_first30.dat.gz")
    scans = list(reader)
    assert isinstance(reader, CoreSlamReader)
    assert len(scans) == 30
    first = scans[0]
    assert len(first) == 683
    assert first.timestamp == 212.387282
    assert scans[-1].timestamp == 215.247717
    assert first.pose is None
    assert first.ranges[153] == 0.007  # an URG error code, in metres
    assert first.ranges[174:177].tolist() == [2.229, 2.217, 2.215]
    assert first.angle_increment == 2 * math.pi / 1024
    assert first.angle_min == pytest.approx(math.radians(-341 * 360 / 1024))
    assert first.angles[-1] == pytest.approx(-first.angle_min)


def test_ranges_are_fields_24_on_in_metres(fixtures) -> None:
    with gzip.open(fixtures / "exp1_first30.dat.gz", "rt") as fh:
        fields = fh.readline().split()
    expected = np.array([int(v) for v in fields[24:]]) / 1000.0
    first = next(iter(open_log(fixtures / "exp1_first30.dat.gz")))
    np.testing.assert_array_equal(first.ranges, expected)


def test_zero_and_error_codes_are_invalid(fixtures) -> None:
    first = next(iter(open_log(fixtures / "exp1_first30.dat.gz")))
    millimetres = np.round(first.ranges * 1000).astype(int)
    assert (millimetres == 0).sum() == 451
    assert ((millimetres > 0) & (millimetres < 20)).sum() == 18
    assert first.valid.sum() == 683 - 451 - 18
    assert first.valid.tolist() == (millimetres >= 20).tolist()


def test_fov_override(fixtures) -> None:
    first = next(iter(open_log(fixtures / "exp1_first30.dat.gz", fov=240.0)))
    assert first.angle_min == pytest.approx(math.radians(-120.0))
    assert first.angles[-1] == pytest.approx(math.radians(120.0))


def test_short_line_names_the_first_missing_field(fixtures) -> None:
    path = fixtures / "coreslam_short_line.dat"
    with pytest.raises(LogFormatError) as caught:
        list(CoreSlamReader(path))
    assert (caught.value.record, caught.value.field) == (1, "range_mm[3]")
    assert "expected 707 fields" in str(caught.value)


def test_beams_option_and_skip_mode(tmp_path) -> None:
    header = "1000000 0 10 20" + " 0" * 20
    path = tmp_path / "small.dat"
    path.write_text(f"{header} 100 200 300 \n{header} 100 x 300 \n{header} 400 500 600 \n")
    reader = CoreSlamReader(path, beams=3, on_error="skip")
    scans = list(reader)
    assert [s.ranges.tolist() for s in scans] == [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]
    assert reader.error_count == 1
    assert "line 2, field range_mm[1]: not a number: 'x'" in reader.errors[0]
