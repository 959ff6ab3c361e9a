"""Seeded mutators of bytes and of text lines.

A mutator takes a ``random.Random`` and the bytes of a file and returns new
bytes; the same generator state gives the same result. Byte mutators apply to
any file, line mutators to text (CARMEN, CoreSLAM, CSV, a bag's
``metadata.yaml``); :func:`inside_gzip` applies one to the content of a gzip
file. The NPZ mutators are in ``mutate_npz.py``, and ``plans.py`` says which
mutators are tried on which seed.
"""

from __future__ import annotations

import gzip
import random
import re
from collections.abc import Callable

Mutator = Callable[[random.Random, bytes], bytes]

HUGE_INTEGERS = {4: (2**31, 2**32 - 1), 8: (2**31, 2**62, 2**64 - 1)}
BAD_NUMBERS = ("nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "abc", "9" * 30, "")
SPAN_LENGTHS = (1, 2, 4, 8, 16, 64, 256, 4096)
NUMBER = re.compile(rb"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
WORD = re.compile(rb"[A-Za-z_][A-Za-z0-9_]*")

# -- bytes ------------------------------------------------------------------------------


def pick_offset(rng: random.Random, size: int) -> int:
    """An offset below ``size``: near the start, near the end (where headers, indexes and
    summaries sit) or anywhere, each a third of the time."""
    if size <= 0:
        return 0
    where = rng.randrange(3)
    if where == 0:
        return rng.randrange(min(size, 512))
    if where == 1:
        return size - 1 - rng.randrange(min(size, 512))
    return rng.randrange(size)


def flip_bits(rng: random.Random, data: bytes) -> bytes:
    out = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if out:
            out[pick_offset(rng, len(out))] ^= 1 << rng.randrange(8)
    return bytes(out)


def overwrite_with(fill: Callable[[random.Random, int], bytes]) -> Mutator:
    def overwrite(rng: random.Random, data: bytes) -> bytes:
        start = pick_offset(rng, len(data))
        length = min(rng.choice(SPAN_LENGTHS), len(data) - start)
        return data[:start] + fill(rng, length) + data[start + length :]

    return overwrite


def insert_nuls(rng: random.Random, data: bytes) -> bytes:
    at = pick_offset(rng, len(data) + 1)
    return data[:at] + b"\x00" * rng.choice((1, 4, 13, 64, 1024)) + data[at:]


def delete_span(rng: random.Random, data: bytes) -> bytes:
    start = pick_offset(rng, len(data))
    return data[:start] + data[start + rng.choice(SPAN_LENGTHS) :]


def duplicate_span(rng: random.Random, data: bytes) -> bytes:
    start = pick_offset(rng, len(data))
    span = data[start : start + rng.choice(SPAN_LENGTHS)]
    return data[:start] + span + data[start:]


def truncate(rng: random.Random, data: bytes) -> bytes:
    return data[: pick_offset(rng, len(data))]


def huge_integer_at(aligned: bool) -> Mutator:
    """Set a 4- or 8-byte little-endian integer to 2^31, 2^32 - 1, 2^62 or 2^64 - 1."""

    def huge_integer(rng: random.Random, data: bytes) -> bytes:
        width = rng.choice((4, 8))
        if len(data) < width:
            return data
        at = pick_offset(rng, len(data) - width + 1)
        if aligned:
            at -= at % width
        value = rng.choice(HUGE_INTEGERS[width]).to_bytes(width, "little")
        return data[:at] + value + data[at + width :]

    return huge_integer


BYTE_MUTATORS: dict[str, Mutator] = {
    "flip_bits": flip_bits,
    "overwrite_random": overwrite_with(lambda rng, n: rng.randbytes(n)),
    "overwrite_ff": overwrite_with(lambda rng, n: b"\xff" * n),
    "overwrite_zero": overwrite_with(lambda rng, n: b"\x00" * n),
    "insert_nuls": insert_nuls,
    "delete_span": delete_span,
    "duplicate_span": duplicate_span,
    "truncate": truncate,
    "huge_integer": huge_integer_at(aligned=True),
    "huge_integer_unaligned": huge_integer_at(aligned=False),
}

# -- lines ------------------------------------------------------------------------------


def line_edit(edit: Callable[[random.Random, list[bytes]], None]) -> Mutator:
    """A mutator editing the list of lines in place."""

    def mutate(rng: random.Random, data: bytes) -> bytes:
        lines = data.split(b"\n")
        edit(rng, lines)
        return b"\n".join(lines)

    return mutate


def pick_line(rng: random.Random, lines: list[bytes], pattern: re.Pattern[bytes]) -> int | None:
    """The index of a random line holding ``pattern``."""
    candidates = [i for i, line in enumerate(lines) if pattern.search(line)]
    return rng.choice(candidates) if candidates else None


def delete_line(rng: random.Random, lines: list[bytes]) -> None:
    del lines[rng.randrange(len(lines))]


def duplicate_line(rng: random.Random, lines: list[bytes]) -> None:
    at = rng.randrange(len(lines))
    lines.insert(at, lines[at])


def swap_lines(rng: random.Random, lines: list[bytes]) -> None:
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]


def bad_number(rng: random.Random, lines: list[bytes]) -> None:
    """Replace one number with ``nan``, ``inf``, ``-1``, ``1e308``, ``abc``, a huge integer..."""
    at = pick_line(rng, lines, NUMBER)
    if at is not None:
        match = rng.choice(list(NUMBER.finditer(lines[at])))
        replacement = rng.choice(BAD_NUMBERS).encode()
        lines[at] = lines[at][: match.start()] + replacement + lines[at][match.end() :]


def rename_keyword(rng: random.Random, lines: list[bytes]) -> None:
    """Change the last letter of a line's first word (``FLASER`` -> ``FLASEX``)."""
    at = pick_line(rng, lines, WORD)
    if at is not None:
        match = WORD.search(lines[at])
        assert match is not None
        last = match.end() - 1
        letter = rng.choice([c for c in b"XQZxqz_" if c != lines[at][last]])
        lines[at] = lines[at][:last] + bytes([letter]) + lines[at][last + 1 :]


def long_line(rng: random.Random, lines: list[bytes]) -> None:
    """Repeat one number of a line thousands of times (a line of up to a few MB)."""
    at = pick_line(rng, lines, NUMBER)
    if at is not None:
        match = rng.choice(list(NUMBER.finditer(lines[at])))
        separator = b"," if b"," in lines[at] else b" "
        extra = (separator + match.group()) * rng.choice((1000, 20_000, 300_000))
        lines[at] = lines[at][: match.end()] + extra + lines[at][match.end() :]


LINE_MUTATORS: dict[str, Mutator] = {
    name: line_edit(edit)
    for name, edit in (
        ("delete_line", delete_line),
        ("duplicate_line", duplicate_line),
        ("swap_lines", swap_lines),
        ("bad_number", bad_number),
        ("rename_keyword", rename_keyword),
        ("long_line", long_line),
    )
}


def inside_gzip(mutator: Mutator) -> Mutator:
    """Mutate the decompressed content and compress it again."""

    def mutate(rng: random.Random, data: bytes) -> bytes:
        return gzip.compress(mutator(rng, gzip.decompress(data)), mtime=0)

    return mutate
