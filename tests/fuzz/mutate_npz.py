"""Seeded mutators of ``.npz`` stacks: odd arrays and damaged ``.npy`` members.

Array mutators load the stack, change one array (a dtype no reader expects,
ragged rows, a wrong shape, a missing or extra key, extreme values) and save it
again; member mutators damage the ``.npy`` header text or bytes of one member
inside an otherwise valid zip. Raw byte damage of the archive is in
``mutate.py``.
"""

from __future__ import annotations

import io
import random
import re
import warnings
import zipfile
from collections.abc import Callable

import numpy as np

from .mutate import BYTE_MUTATORS, Mutator


def load_arrays(data: bytes) -> dict[str, np.ndarray]:
    with np.load(io.BytesIO(data)) as archive:
        return {key: archive[key] for key in archive.files}


def save_arrays(arrays: dict[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def array_edit(edit: Callable[[random.Random, dict[str, np.ndarray]], None]) -> Mutator:
    """A mutator editing the arrays of an ``.npz`` in place."""

    def mutate(rng: random.Random, data: bytes) -> bytes:
        arrays = load_arrays(data)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            edit(rng, arrays)
        return save_arrays(arrays)

    return mutate


def odd_dtype(rng: random.Random, like: np.ndarray) -> np.ndarray:
    """An array of ``like``'s shape but of a dtype no reader expects."""
    shape = like.shape
    kind = rng.choice(
        (
            "str",
            "bytes",
            "complex",
            "object",
            "bool",
            "int8",
            "uint64",
            "float16",
            "datetime",
            "structured",
            "void",
        )
    )
    if kind in ("str", "bytes"):
        text = rng.choice(("abc", "1.5", "nan", ""))
        return np.full(shape, text, dtype="U8" if kind == "str" else "S8")
    if kind == "complex":
        return like.astype(complex) + 1j
    if kind == "object":
        filled = np.empty(shape, dtype=object)
        filled.fill(rng.choice((None, 1.0, "abc", [1.0, 2.0])))
        return filled
    if kind == "datetime":
        return np.zeros(shape, dtype="datetime64[s]")
    if kind == "structured":
        return np.zeros(shape, dtype=[("x", "<f4"), ("y", "<i4")])
    if kind == "void":
        return np.zeros(shape, dtype="V3")
    return np.nan_to_num(like.astype(float)).astype(kind)


def wrong_dtype(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    key = rng.choice(sorted(arrays))
    arrays[key] = odd_dtype(rng, arrays[key])


def ragged(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    """Rows of different lengths (an object array)."""
    key = rng.choice(("ranges", "ranges", "poses", "timestamps"))
    rows = [np.ones(rng.randrange(1, 200)) for _ in range(len(arrays["ranges"]))]
    arrays[key] = np.empty(len(rows), dtype=object)
    arrays[key][:] = rows


def wrong_shape(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    key = rng.choice(sorted(arrays))
    a = arrays[key]
    reshape = rng.choice(
        (
            lambda: a[..., None],
            lambda: np.stack([a, a]),
            lambda: a[:0] if a.ndim else a[None][:0],
            lambda: a[:-1] if a.ndim else a[None],
            lambda: np.array(a.flat[0]) if a.size else np.array(1.0),
            lambda: a.T,
            lambda: np.asfortranarray(a),
            lambda: np.zeros((len(arrays["ranges"]), 0)),
            lambda: np.zeros((0, 0)),
            lambda: np.ones((1, 1, 1, 1)),
        )
    )
    arrays[key] = reshape()


def drop_key(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    del arrays[rng.choice(sorted(arrays))]


def add_key(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    """Add an optional key the reader uses, of a plausible or wrong shape."""
    scans, beams = arrays["ranges"].shape[0], arrays["ranges"].shape[-1]
    key = rng.choice(("valid", "intensities", "range_min", "timestamp", "pose", "odom_pose"))
    shape = rng.choice(((scans, beams), (scans,), (), (beams,), (scans, 3), (3,)))
    dtype = rng.choice(("uint8", "float32", "float64"))
    arrays[key] = np.asarray(rng.choice((0, 1, -1, np.nan, np.inf)) * np.ones(shape), dtype=dtype)


def extreme_values(rng: random.Random, arrays: dict[str, np.ndarray]) -> None:
    key = rng.choice(sorted(arrays))
    value = rng.choice((np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, -1.0, 5e-324))
    if arrays[key].dtype.kind == "f":
        arrays[key] = np.full_like(arrays[key], value)


def zip_members(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def rezip(members: dict[str, bytes]) -> bytes:
    """A valid zip (fresh CRCs) of ``members``, so only the ``.npy`` content is damaged."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    return buffer.getvalue()


def damage_header(rng: random.Random, header: bytes) -> bytes:
    """Damage the text of a ``.npy`` header dict (``{'descr': ..., 'shape': (...), }``)."""
    damage = rng.choice(
        (
            lambda: header.replace(b"}", b"", 1),
            lambda: header.replace(b"{", b"", 1),
            lambda: header.replace(b"'", b"", 1),
            lambda: re.sub(rb"\(\d+", b"(99999999999", header, count=1),
            lambda: re.sub(rb"\([^)]*\)", b"(-1,)", header, count=1),
            lambda: re.sub(rb"\([^)]*\)", b"(" + b"9" * 25 + b",)", header, count=1),
            lambda: re.sub(
                rb"'[<>|]\w+'",
                rng.choice((b"'<f16'", b"'|O'", b"'xyz'", b"'<U0'")),
                header,
                count=1,
            ),
            lambda: header.replace(b"False", b"True"),
            lambda: header.replace(b"shape", b"shaep"),
            lambda: (header[:-1] + b"\\" + b"\n") if header else header,
        )
    )
    return damage()


def npy_header_damage(rng: random.Random, data: bytes) -> bytes:
    members = zip_members(data)
    name = rng.choice(sorted(members))
    npy = members[name]
    if rng.random() < 0.2:  # the header length field or the format version
        start = rng.choice((6, 7, 8, 9))
        members[name] = npy[:start] + bytes([rng.choice((0, 3, 0x7F, 0xFF))]) + npy[start + 1 :]
        return rezip(members)
    length = int.from_bytes(npy[8:10], "little")
    header = damage_header(rng, npy[10 : 10 + length])
    members[name] = npy[:8] + len(header).to_bytes(2, "little") + header + npy[10 + length :]
    return rezip(members)


def npy_member_bytes(rng: random.Random, data: bytes) -> bytes:
    """A byte mutator applied to one ``.npy`` member, in a zip with valid CRCs."""
    members = zip_members(data)
    name = rng.choice(sorted(members))
    mutator = BYTE_MUTATORS[rng.choice(sorted(BYTE_MUTATORS))]
    members[name] = mutator(rng, members[name])
    return rezip(members)


NPZ_MUTATORS: dict[str, Mutator] = {
    "npz_wrong_dtype": array_edit(wrong_dtype),
    "npz_ragged": array_edit(ragged),
    "npz_wrong_shape": array_edit(wrong_shape),
    "npz_drop_key": array_edit(drop_key),
    "npz_add_key": array_edit(add_key),
    "npz_extreme_values": array_edit(extreme_values),
    "npy_header_damage": npy_header_damage,
    "npy_member_bytes": npy_member_bytes,
}
