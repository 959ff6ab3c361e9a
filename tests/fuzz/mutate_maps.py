"""Seeded mutators of map inputs: the poses of a CARMEN log, and a TUM trajectory file.

A map input is a folder holding ``log.clf`` (a CARMEN excerpt with poses) and, for the
``map-log-tum`` seed, ``poses.tum`` (its poses as a TUM file). The pose mutators move
the world's origin far away (the same trajectory shifted by 10^4 to 10^300 m), damage one
pose (NaN, inf, huge) or make the trajectory jump; the TUM mutators add duplicate
timestamps (with the same pose or another), huge or non-finite fields, a zero quaternion,
times outside the log's, and the generic line and byte mutators of ``mutate.py``.
"""

from __future__ import annotations

import random

from .mutate import BYTE_MUTATORS, LINE_MUTATORS, Mutator

#: Offsets of the world's origin (metres): within the map's limits, and beyond them.
OFFSETS = (1e4, 1e5, 5e6, 1e7, 1e8, 1e9 - 50.0, 1e9 + 1.0, 1e15, 1e300)
#: Values one pose field is set to.
BAD_POSE_VALUES = ("nan", "inf", "-inf", "1e308", "-1e308", "1000000001", "-1e15", "2e5", "1e10")
#: Jumps of a trajectory part of the way through (metres).
JUMPS = (50.0, 9e4, 1.1e5, 1e6, 1e9)


def _lines(data: bytes) -> list[list[str]]:
    return [line.split(" ") for line in data.decode("utf-8", "replace").split("\n")]


def _join(lines: list[list[str]]) -> bytes:
    return "\n".join(" ".join(fields) for fields in lines).encode()


def _pose_columns(fields: list[str]) -> int | None:
    """The index of the laser pose's x in a ``FLASER``/``RLASER`` line, or None."""
    if fields[0] not in ("FLASER", "RLASER") or len(fields) < 2 or not fields[1].isdigit():
        return None
    at = 2 + int(fields[1])
    return at if len(fields) >= at + 6 else None


def _move(fields: list[str], at: int, dx: float, dy: float) -> None:
    for k, d in ((at, dx), (at + 1, dy), (at + 3, dx), (at + 4, dy)):
        fields[k] = repr(float(fields[k]) + d)


def shift_poses(rng: random.Random, data: bytes) -> bytes:
    """Every pose moved by one offset (x, y or both, either sign)."""
    offset = rng.choice(OFFSETS)
    sx, sy = rng.choice(((1, 1), (1, 0), (0, 1), (-1, -1), (1, -1)))
    lines = _lines(data)
    for fields in lines:
        at = _pose_columns(fields)
        if at is not None:
            _move(fields, at, sx * offset, sy * offset)
    return _join(lines)


def bad_pose(rng: random.Random, data: bytes) -> bytes:
    """One field of one scan's poses (laser or robot x, y, theta) set to a bad value."""
    lines = _lines(data)
    candidates = [k for k, fields in enumerate(lines) if _pose_columns(fields) is not None]
    if candidates:
        fields = lines[rng.choice(candidates)]
        at = _pose_columns(fields)
        assert at is not None
        fields[at + rng.randrange(6)] = rng.choice(BAD_POSE_VALUES)
    return _join(lines)


def jump_poses(rng: random.Random, data: bytes) -> bytes:
    """The trajectory jumps by a distance part of the way through, and stays there."""
    lines = _lines(data)
    posed = [k for k, fields in enumerate(lines) if _pose_columns(fields) is not None]
    if posed:
        start, jump = rng.choice(posed), rng.choice(JUMPS)
        for fields in lines[start:]:
            at = _pose_columns(fields)
            if at is not None:
                _move(fields, at, jump, 0.0)
    return _join(lines)


def spin_poses(rng: random.Random, data: bytes) -> bytes:
    """Every heading turned by a huge angle (radians far outside one turn)."""
    turn = rng.choice((1e6, -1e12, 1e300))
    lines = _lines(data)
    for fields in lines:
        at = _pose_columns(fields)
        if at is not None:
            fields[at + 2] = repr(float(fields[at + 2]) + turn)
    return _join(lines)


POSE_MUTATORS: dict[str, Mutator] = {
    "shift_poses": shift_poses,
    "bad_pose": bad_pose,
    "jump_poses": jump_poses,
    "spin_poses": spin_poses,
}

# -- TUM files --------------------------------------------------------------------------


def _tum_rows(data: bytes) -> tuple[list[list[str]], list[int]]:
    lines = _lines(data)
    rows = [k for k, fields in enumerate(lines) if len(fields) == 8 and fields[0][:1] != "#"]
    return lines, rows


def duplicate_time_other_pose(rng: random.Random, data: bytes) -> bytes:
    """A second line at a pose line's timestamp, with another position."""
    lines, rows = _tum_rows(data)
    if rows:
        at = rng.choice(rows)
        copy = list(lines[at])
        copy[1] = repr(float(copy[1]) + rng.choice((0.5, 1e-6, 100.0)))
        lines.insert(rng.randrange(len(lines) + 1), copy)
    return _join(lines)


def duplicate_time_same_pose(rng: random.Random, data: bytes) -> bytes:
    """A pose line repeated elsewhere in the file (the same timestamp and pose)."""
    lines, rows = _tum_rows(data)
    if rows:
        lines.insert(rng.randrange(len(lines) + 1), list(lines[rng.choice(rows)]))
    return _join(lines)


def shift_trajectory(rng: random.Random, data: bytes) -> bytes:
    """Every position moved by one offset."""
    offset = rng.choice(OFFSETS)
    lines, rows = _tum_rows(data)
    for k in rows:
        for column in (1, 2):
            lines[k][column] = repr(float(lines[k][column]) + offset)
    return _join(lines)


def bad_tum_field(rng: random.Random, data: bytes) -> bytes:
    """One field of one pose line set to a bad value."""
    lines, rows = _tum_rows(data)
    if rows:
        lines[rng.choice(rows)][rng.randrange(8)] = rng.choice((*BAD_POSE_VALUES, "", "abc"))
    return _join(lines)


def zero_quaternion(rng: random.Random, data: bytes) -> bytes:
    lines, rows = _tum_rows(data)
    if rows:
        lines[rng.choice(rows)][4:8] = ["0", "0", "0", "0"]
    return _join(lines)


def shift_times(rng: random.Random, data: bytes) -> bytes:
    """Every timestamp moved (outside the log's times, or reversed)."""
    lines, rows = _tum_rows(data)
    shift = rng.choice((1e6, -1e6, 0.02, 1e300))
    for k in rows:
        lines[k][0] = repr(float(lines[k][0]) + shift) if shift != 1e300 else f"-{lines[k][0]}"
    return _join(lines)


TUM_MUTATORS: dict[str, Mutator] = {
    "duplicate_time_other_pose": duplicate_time_other_pose,
    "duplicate_time_same_pose": duplicate_time_same_pose,
    "shift_trajectory": shift_trajectory,
    "bad_tum_field": bad_tum_field,
    "zero_quaternion": zero_quaternion,
    "shift_times": shift_times,
    **LINE_MUTATORS,
    **{name: BYTE_MUTATORS[name] for name in ("flip_bits", "truncate", "insert_nuls")},
}
