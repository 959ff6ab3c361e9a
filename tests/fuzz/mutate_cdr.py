"""Seeded mutators of one ``sensor_msgs/LaserScan`` DDS sample (its CDR bytes).

The seed is a scan of the shipped Intel sample as the node receives it: the 4-byte
encapsulation header, then the message in little-endian CDR (``frame_id`` a length, its
UTF-8 bytes and a NUL; ``ranges`` and ``intensities`` a length and float32 values). The
structure-aware mutators know where the lengths, the text and the header are; the byte
mutators of ``mutate.py`` damage anything. The same generator state gives the same bytes.
"""

from __future__ import annotations

import itertools
import random
import struct
from dataclasses import dataclass

from .mutate import BYTE_MUTATORS, Mutator

#: Encapsulation identifiers (big-endian bytes 0-1): CDR BE/LE, PL_CDR BE/LE, XCDR2 (plain,
#: delimited, parameter list) BE/LE, and ones no DDS defines.
ENCAPSULATIONS = (0x0000, 0x0001, 0x0002, 0x0003, 0x0006, 0x0007, 0x0008, 0x0009, 0x000A,
                  0x000B, 0x0004, 0x0100, 0xFFFF)  # fmt: skip
LENGTHS = (0, 1, 2**31 - 1, 2**31, 2**32 - 1, 0x7FFF_FFF0, 65_536)
NOT_UTF8 = (b"\xff", b"\xfe\xff", b"\x80", b"\xc3\x28", b"\xed\xa0\x80", b"\xf8\x88\x80\x80\x80",
            b"\xe2\x82", b"\xc0\xaf")  # fmt: skip
BAD_FLOATS = (float("nan"), float("inf"), float("-inf"), 0.0, -0.0, 1e-45, 3.4e38, -3.4e38)
#: Characters of the long ``frame_id`` mutations: one datagram, fragments, a megabyte.
LONG_FRAMES = (1_000, 50_000, 1_000_000)
FLOAT_FIELDS = ("angle_min", "angle_max", "angle_increment", "time_increment", "scan_time",
                "range_min", "range_max")  # fmt: skip


@dataclass(frozen=True)
class Layout:
    """Where the fields of a well-formed LaserScan sample are (offsets into its bytes)."""

    frame_length: int  # the uint32 length of frame_id (its bytes and the NUL)
    frame_end: int  # just past the NUL
    floats: int  # angle_min, then the six other float32 fields
    ranges_length: int
    intensities_length: int

    @property
    def frame_text(self) -> tuple[int, int]:
        return self.frame_length + 4, self.frame_end - 1


def layout_of(sample: bytes) -> Layout:
    """The :class:`Layout` of a well-formed little-endian LaserScan sample."""
    frame_length = 4 + 8
    (length,) = struct.unpack_from("<I", sample, frame_length)
    frame_end = frame_length + 4 + length
    floats = frame_end + (-(frame_end - 4)) % 4  # CDR aligns to 4 from after the header
    ranges_length = floats + 4 * len(FLOAT_FIELDS)
    (beams,) = struct.unpack_from("<I", sample, ranges_length)
    return Layout(frame_length, frame_end, floats, ranges_length, ranges_length + 4 + 4 * beams)


def seed_sample(beams: int = 180) -> bytes:
    """The first Intel scan (``beams`` beams, cycled), with intensities, as CDR bytes."""
    from scanlines.data import sample
    from scanlines.io import open_log
    from scanlines.ros2 import convert

    with open_log(sample("intel")) as reader:
        scan = next(iter(reader))
    message = convert.laser_scan(scan, "laser")
    ranges = list(itertools.islice(itertools.cycle(message.ranges), beams))
    step = message.angle_increment
    message.ranges = ranges
    message.intensities = [float(k % 7) for k in range(beams)]
    message.angle_max = message.angle_min + (beams - 1) * step
    return message.serialize()


def _put(data: bytes, at: int, value: bytes) -> bytes:
    return data[:at] + value + data[at + len(value) :]


def huge_length(rng: random.Random, data: bytes) -> bytes:
    """A sequence or string length set to 0, 1, 2^31, 2^32 - 1..."""
    lay = layout_of(data)
    at = rng.choice((lay.frame_length, lay.ranges_length, lay.intensities_length))
    return _put(data, at, struct.pack("<I", rng.choice(LENGTHS)))


def length_off_by_one(rng: random.Random, data: bytes) -> bytes:
    """A sequence or string length one more or one less than its content."""
    lay = layout_of(data)
    at = rng.choice((lay.frame_length, lay.ranges_length, lay.intensities_length))
    (length,) = struct.unpack_from("<I", data, at)
    return _put(data, at, struct.pack("<I", max(0, length + rng.choice((-1, 1)))))


def bad_encapsulation(rng: random.Random, data: bytes) -> bytes:
    """Another encapsulation identifier (big-endian over little-endian bytes, XCDR2, a
    parameter list, an unknown one), and sometimes nonzero options."""
    options = rng.choice((b"\x00\x00", b"\x00\x03", rng.randbytes(2)))
    return struct.pack(">H", rng.choice(ENCAPSULATIONS)) + options + data[4:]


def not_utf8(rng: random.Random, data: bytes) -> bytes:
    """Bytes of frame_id that are no UTF-8 (same length: the CDR stays well formed)."""
    start, end = layout_of(data).frame_text
    bad = rng.choice(NOT_UTF8)[: end - start]
    at = rng.randrange(start, end - len(bad) + 1)
    return _put(data, at, bad)


def missing_nul(rng: random.Random, data: bytes) -> bytes:
    """frame_id's terminating NUL replaced (or a NUL inside the text)."""
    lay = layout_of(data)
    start, end = lay.frame_text
    at = end if rng.random() < 0.7 else rng.randrange(start, end)
    return _put(data, at, b"\x00" if at < end else bytes([rng.randrange(1, 256)]))


def long_frame(rng: random.Random, data: bytes) -> bytes:
    """frame_id rebuilt with a thousand to a million characters (sometimes not UTF-8)."""
    lay = layout_of(data)
    text = rng.choice((b"f", b"\xc3\xa9", b"\xff")) * rng.choice(LONG_FRAMES)
    frame = struct.pack("<I", len(text) + 1) + text + b"\x00"
    frame += b"\x00" * ((-(lay.frame_length + len(frame) - 4)) % 4)
    return data[: lay.frame_length] + frame + data[lay.floats :]


def bad_float(rng: random.Random, data: bytes) -> bytes:
    """An angle, time or range limit set to NaN, an infinity, zero, a denormal, 3.4e38."""
    lay = layout_of(data)
    at = lay.floats + 4 * rng.randrange(len(FLOAT_FIELDS))
    return _put(data, at, struct.pack("<f", rng.choice(BAD_FLOATS)))


def beams_mismatch(rng: random.Random, data: bytes) -> bytes:
    """ranges (or intensities) with fewer or more values than the angles say, the CDR
    well formed."""
    lay = layout_of(data)
    at = rng.choice((lay.ranges_length, lay.intensities_length))
    (beams,) = struct.unpack_from("<I", data, at)
    new = rng.choice((0, 1, beams // 2, beams + 1, 4 * beams))
    values = data[at + 4 : at + 4 + 4 * beams]
    values = (values * (new // max(beams, 1) + 1))[: 4 * new]
    return data[:at] + struct.pack("<I", new) + values + data[at + 4 + 4 * beams :]


def trailing_bytes(rng: random.Random, data: bytes) -> bytes:
    """Bytes after the message's end."""
    return data + rng.randbytes(rng.choice((1, 3, 4, 64, 4096)))


def tiny(rng: random.Random, data: bytes) -> bytes:
    """Only the first 0 to 8 bytes (an empty payload, a header alone...)."""
    return data[: rng.randrange(9)]


CDR_MUTATORS: dict[str, Mutator] = {
    "huge_length": huge_length,
    "length_off_by_one": length_off_by_one,
    "bad_encapsulation": bad_encapsulation,
    "not_utf8": not_utf8,
    "missing_nul": missing_nul,
    "long_frame": long_frame,
    "bad_float": bad_float,
    "beams_mismatch": beams_mismatch,
    "trailing_bytes": trailing_bytes,
    "tiny": tiny,
}


def plans() -> list[tuple[str, Mutator]]:
    """Every mutator of a LaserScan sample, the structure-aware and the byte ones
    alternating (so that a short run tries some of each)."""
    structured = [(f"cdr/{name}", m) for name, m in CDR_MUTATORS.items()]
    raw = [(f"bytes/{name}", m) for name, m in BYTE_MUTATORS.items()]
    return [plan for pair in itertools.zip_longest(structured, raw) for plan in pair if plan]
