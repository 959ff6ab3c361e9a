"""The compiled number reader of text records: exactly ``float(token)`` or not read at all."""

from __future__ import annotations

import gzip
import math
import struct

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from scanlines.data import sample
from scanlines.io import CarmenReader, open_log
from scanlines.io.numbers import DECIMAL, INTEGER, NOT_A_NUMBER, number_fields


def _bits(value: float) -> bytes:
    return struct.pack("<d", value)


def _check_token(token: str, value: float, kind: int) -> None:
    """A token read as a number is the double ``float`` gives, sign of zero included."""
    try:
        expected = float(token)
    except ValueError:
        assert kind == NOT_A_NUMBER
        return
    if kind == NOT_A_NUMBER:
        assert math.isnan(value)
        return
    assert _bits(value) == _bits(expected), (token, value, expected)
    if kind == INTEGER:
        assert int(token) == expected


FORMATS = ["{!r}", "{:.2f}", "{:.6f}", "{:.15g}", "{:.17g}", "{:e}", "{:.3E}", "{:+.4f}"]


@settings(deadline=None)  # the first call loads the kernel
@given(st.floats(allow_nan=False, allow_infinity=False), st.sampled_from(FORMATS))
@example(0.1, "{!r}")
@example(-0.0, "{!r}")
@example(81.83, "{:.2f}")
@example(1234567890.123456, "{:.6f}")
@example(9007199254740993.0, "{:.0f}")  # 2^53 + 1: beyond the exact significands
def test_formatted_floats_read_as_float_reads_them(number, fmt) -> None:
    token = fmt.format(number)
    fields = number_fields(token)
    assert fields is not None
    assert len(fields) == 1
    _check_token(token, float(fields.values[0]), int(fields.kinds[0]))


@settings(deadline=None)
@given(st.text(alphabet="0123456789+-.eE_xn", min_size=1, max_size=24))
@example("1e22")
@example("1e23")
@example("9007199254740992")  # 2^53
@example("0.30000000000000004")
@example("1_000")
@example(".")
@example("-")
@example("1e")
@example("+.5e-3")
def test_any_token_reads_as_float_or_not_at_all(token) -> None:
    fields = number_fields(token)
    assert fields is not None
    assert len(fields) == 1
    _check_token(token, float(fields.values[0]), int(fields.kinds[0]))


@settings(deadline=None)
@given(st.lists(st.text(alphabet="0123456789.-e abc\t\x0b\x0c\r\x1c\x1f", max_size=12), max_size=8))
def test_tokens_are_those_str_split_gives(parts) -> None:
    line = " ".join(parts)
    fields = number_fields(line)
    tokens = line.split()
    assert fields is not None
    assert len(fields) == len(tokens)
    for token, value, kind in zip(tokens, fields.values, fields.kinds, strict=True):
        _check_token(token, float(value), int(kind))
    assert fields.texts == [k for k, kind in enumerate(fields.kinds) if kind == NOT_A_NUMBER]


def test_kinds_and_a_line_that_is_not_ascii() -> None:
    fields = number_fields("FLASER 180 2.5 -3e2 host")
    assert fields is not None
    assert fields.kinds.tolist() == [NOT_A_NUMBER, INTEGER, DECIMAL, DECIMAL, NOT_A_NUMBER]
    assert fields.values[1:4].tolist() == [180.0, 2.5, -300.0]
    assert fields.texts == [0, 4]
    assert number_fields("FLASER 1 2.5 h\u00f6st") is None


def _laser_lines(path) -> list[tuple[int, str]]:
    with gzip.open(path, "rt") as handle:
        return [(k, line) for k, line in enumerate(handle, 1) if line.startswith("FLASER")]


def _same_scan(a, b) -> None:
    assert a.ranges.tobytes() == b.ranges.tobytes()
    assert (a.angle_min, a.angle_increment, a.range_min, a.range_max) == (
        b.angle_min,
        b.angle_increment,
        b.range_min,
        b.range_max,
    )
    assert (a.timestamp, a.pose) == (b.timestamp, b.pose)


def test_fast_flaser_records_are_the_split_records() -> None:
    """Every record of both shipped CARMEN excerpts, read in one compiled pass and read
    token by token, gives the same scan to the bit."""
    for name in ("intel", "freiburg"):
        reader = CarmenReader(sample(name))
        reader.message  # noqa: B018 - detect the message
        lines = _laser_lines(sample(name))
        assert lines
        for line_number, line in lines:
            fast = reader._fast_flaser(number_fields(line), line_number)
            assert fast is not None, line_number
            _same_scan(fast, reader._parse_laser(line.split(), line_number))


def test_records_the_fast_path_cannot_read_are_read_token_by_token(tmp_path) -> None:
    """Values outside the fast path (``nan``, ``inf``, 17 significant digits, a bad field)
    fall back to the split reader: same scans, same errors."""
    ranges = ["1.5", "nan", "2.25000000000000001", "inf", "3"]
    good = f"FLASER 5 {' '.join(ranges)} 0 0 0 0 0 0 10.5 host 10.5\n"
    bad = "FLASER 5 1.5 x 2 3 4 0 0 0 0 0 0 11.5 host 11.5\n"
    path = tmp_path / "odd.log"
    path.write_text(good + bad)
    reader = CarmenReader(path, on_error="skip")
    scans = list(reader)
    assert len(scans) == 1
    expected = np.array([float(r) for r in ranges])
    np.testing.assert_array_equal(scans[0].ranges, expected)
    assert reader.error_count == 1
    assert reader._fast_flaser(number_fields(good), 1) is None


def _record(message: str, ranges: list[float], remissions: list[float], numbers: list[float]):
    """A laser record of ``message`` (values formatted as a logger might write them)."""
    text = " ".join(f"{v:.3f}" for v in ranges)
    stamps = f"{numbers[0]:.6f} host {numbers[1]:.6f}"
    if message == "FLASER":
        return f"FLASER {len(ranges)} {text} 1.5 -2.25 0.125 1.0 -2.0 0.25 {stamps}\n"
    header = "0 -1.570796 3.141593 0.017453 80.0 0.01 0"
    middle = f"{len(ranges)} {text} {len(remissions)} {' '.join(f'{v:.1f}' for v in remissions)}"
    tail = " 1.5 -2.25 0.125 1.0 -2.0 0.25 0.3 0.0 0.5 0.2 0.0" if message == "ROBOTLASER1" else ""
    return f"{message} {header} {middle}{tail} {stamps}\n"


@settings(max_examples=40, deadline=None)
@given(
    st.sampled_from(["FLASER", "ROBOTLASER1", "RAWLASER1"]),
    st.lists(st.floats(0.0, 81.9), min_size=1, max_size=40),
    st.integers(0, 3),
    st.lists(st.floats(0.0, 2e9), min_size=2, max_size=2),
)
def test_each_laser_message_reads_the_same_either_way(tmp_path_factory, message, ranges, m, stamps):
    remissions = ranges[:m] if m < 3 else [float(k) for k in range(len(ranges))]
    line = _record(message, ranges, remissions, stamps)
    path = tmp_path_factory.mktemp("laser") / "one.log"
    path.write_text(line)
    reader = CarmenReader(path)
    reader.message  # noqa: B018 - detect the message
    fields = number_fields(line)
    assert fields is not None
    fast = (reader._fast_flaser if message == "FLASER" else reader._fast_new_laser)(fields, 1)
    assert fast is not None
    slow = reader._parse_laser(line.split(), 1)
    _same_scan(fast, slow)
    assert (fast.intensities is None) == (slow.intensities is None)
    if fast.intensities is not None:
        assert fast.intensities.tobytes() == slow.intensities.tobytes()
    _same_scan(next(iter(CarmenReader(path))), slow)


def test_a_negative_count_goes_to_the_slow_path(tmp_path) -> None:
    line = "FLASER -5 1 2 3 host 4\n"
    path = tmp_path / "negative.log"
    path.write_text("FLASER 1 2.0 0 0 0 0 0 0 1.0 host 1.0\n" + line)
    reader = CarmenReader(path, on_error="skip")
    assert reader._fast_flaser(number_fields(line), 2) is None
    assert len(list(reader)) == 1
    assert reader.error_count == 1


def test_coreslam_records_are_the_split_records() -> None:
    reader = open_log(sample("urg"))
    with gzip.open(sample("urg"), "rt") as handle:
        lines = [line for line in handle if line.strip() and not line.startswith("#")]
    assert lines
    for line_number, line in enumerate(lines, 1):
        fields = number_fields(line)
        assert fields is not None
        assert not fields.texts
        _same_scan(reader._parse_line(line, line_number), reader._parse(line.split(), line_number))
