"""Stacks of scans in a numpy ``.npz`` archive.

Keys
----
``ranges``
    ``S x N`` (``S`` scans of ``N`` beams) or ``N`` (one scan), metres.
``angle_min``, ``angle_increment``
    Radians; a scalar or one value per scan (shape ``S``). Required.
``range_min``, ``range_max``
    Optional, scalar or per scan (default 0 and infinity).
``timestamps`` or ``timestamp``
    Optional, shape ``S`` (or scalar for one scan), seconds; ``NaN`` -> ``None``.
``poses`` or ``pose``, else ``odom_pose``
    Optional, ``S x 3`` (or ``3`` for one scan): sensor ``(x, y, theta)``.
    Rows with a ``NaN`` give ``pose=None``.
``valid``
    Optional ``S x N`` mask; beams where it is 0 get ``NaN`` (no return) in
    a copy of the ranges. This reads the layout of the shared
    ``intel_every5th_fullrun.npz`` (``ranges`` float32, ``valid`` uint8,
    ``odom_pose``, ``timestamp`` partly ``NaN``), whose ``odom_pose`` is the
    robot's odometry pose (the laser sits at the robot origin there).
``intensities``
    Optional ``S x N``.

Other keys are ignored (listed by :meth:`NpzReader.info`).

Streaming: per-scan arrays are read row by row straight out of the zip member
(compressed or not), so memory stays at one row per key whatever the file
size. Only Fortran-ordered arrays fall back to loading the whole key. Object
arrays (pickles) are refused.
"""

from __future__ import annotations

import math
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from scanlines.errors import LogFormatError
from scanlines.io.base import ErrorPolicy, LogReader
from scanlines.scan import Scan

__all__ = ["NpzReader"]

_PER_BEAM_KEYS = ("ranges", "valid", "intensities")
_TIMESTAMP_KEYS = ("timestamps", "timestamp")
_POSE_KEYS = ("poses", "pose", "odom_pose")
_SCALAR_KEYS = ("angle_min", "angle_increment", "range_min", "range_max")
_DEFAULTS = {"range_min": 0.0, "range_max": math.inf}


class _NpyHeader:
    """Shape and dtype of one ``.npy`` member, read without loading its data."""

    def __init__(self, shape: tuple[int, ...], dtype: np.dtype, fortran: bool) -> None:
        self.shape = shape
        self.dtype = dtype
        self.fortran = fortran


def _read_header(fh: IO[bytes]) -> _NpyHeader:
    version = np.lib.format.read_magic(fh)
    if version == (1, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
    else:
        shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
    return _NpyHeader(tuple(shape), np.dtype(dtype), bool(fortran))


class NpzReader(LogReader):
    """Stream the scans of an ``.npz`` stack (see the module docstring for the keys).

    Parameters
    ----------
    path:
        The archive.
    on_error:
        ``"fail"`` or ``"skip"`` scans whose values are unusable (e.g. a zero
        ``angle_increment`` in one row).

    Raises
    ------
    LogFormatError
        When the archive cannot be opened, ``ranges`` or an angle key is
        missing, or a key's shape does not match ``ranges``.
    """

    format_name = "npz"

    def __init__(self, path: str | Path, *, on_error: ErrorPolicy = "fail") -> None:
        super().__init__(path, on_error=on_error)
        self.headers = self._read_headers()
        self.n_scans, self.n_beams = self._check_layout()

    # -- layout ---------------------------------------------------------------------------

    def _open_zip(self) -> zipfile.ZipFile:
        try:
            return zipfile.ZipFile(self.path)
        except (zipfile.BadZipFile, OSError) as exc:
            raise LogFormatError(f"not a readable .npz archive ({exc})", path=self.path) from None

    def _read_headers(self) -> dict[str, _NpyHeader]:
        headers: dict[str, _NpyHeader] = {}
        with self._open_zip() as archive:
            for member in archive.namelist():
                if not member.endswith(".npy"):
                    continue
                try:
                    with archive.open(member) as fh:
                        headers[member[:-4]] = _read_header(fh)
                except (ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
                    raise LogFormatError(
                        f"unreadable array ({exc})", path=self.path, field=member[:-4]
                    ) from None
        return headers

    def _check_layout(self) -> tuple[int, int]:
        if "ranges" not in self.headers:
            raise LogFormatError(
                f"no 'ranges' array (keys: {', '.join(sorted(self.headers)) or 'none'})",
                path=self.path,
                field="ranges",
            )
        shape = self.headers["ranges"].shape
        if len(shape) not in (1, 2):
            raise LogFormatError(
                f"must be S x N or N, got shape {shape}", path=self.path, field="ranges"
            )
        n_scans, n_beams = (1, shape[0]) if len(shape) == 1 else shape
        single = len(shape) == 1
        for key, header in self.headers.items():
            if header.dtype.hasobject:
                raise LogFormatError("object arrays are not read", path=self.path, field=key)
        for key in ("angle_min", "angle_increment"):
            if key not in self.headers:
                raise LogFormatError("missing (radians)", path=self.path, field=key)
        expected: dict[str, list[tuple[int, ...]]] = {
            **{k: [shape] for k in _PER_BEAM_KEYS},
            **{k: [(), (n_scans,)] for k in (*_SCALAR_KEYS, *_TIMESTAMP_KEYS)},
            **{k: [(n_scans, 3)] + [(3,)] * single for k in _POSE_KEYS},
        }
        for key in self._used_keys():
            if self.headers[key].shape not in expected[key]:
                allowed = " or ".join(str(s) for s in expected[key])
                raise LogFormatError(
                    f"shape {self.headers[key].shape} does not fit ranges {shape}: "
                    f"expected {allowed}",
                    path=self.path,
                    field=key,
                )
        return n_scans, n_beams

    def _used_keys(self) -> list[str]:
        keys = [k for k in (*_PER_BEAM_KEYS, *_SCALAR_KEYS) if k in self.headers]
        for group in (_TIMESTAMP_KEYS, _POSE_KEYS):
            keys += [k for k in group if k in self.headers][:1]
        return keys

    def info(self) -> dict[str, Any]:
        """Metadata known from the array headers: scan and beam counts, keys used and ignored."""
        used = self._used_keys()
        return {
            **super().info(),
            "scans_in_file": self.n_scans,
            "beams": self.n_beams,
            "keys": used,
            "ignored_keys": sorted(set(self.headers) - set(used)),
        }

    # -- streaming ------------------------------------------------------------------------

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        with self._open_zip() as archive:
            streams = {key: self._rows(archive, key) for key in self._used_keys()}
            try:
                for index in range(self.n_scans):
                    row = {key: next(stream) for key, stream in streams.items()}
                    try:
                        scan = self._scan(index, row)
                    except LogFormatError as error:
                        self._bad_record(error)
                        continue
                    self.counts["scan"] += 1
                    yield index, scan
            finally:
                for stream in streams.values():
                    stream.close()

    def _rows(self, archive: zipfile.ZipFile, key: str) -> Iterator[np.ndarray]:
        """One row per scan of ``key``; a scalar (or 1-scan) array is repeated."""
        header = self.headers[key]
        per_scan = self._is_per_scan(key, header.shape)
        if not per_scan:
            value = self._load(archive, key)
            while True:
                yield value
        if header.fortran:  # rows are not contiguous on disk: load the key once
            yield from self._load(archive, key)
            return
        row_shape = header.shape[1:]
        row_bytes = int(np.prod(row_shape, dtype=np.int64)) * header.dtype.itemsize
        with archive.open(f"{key}.npy") as fh:
            _read_header(fh)
            for index in range(self.n_scans):
                data = fh.read(row_bytes)
                if len(data) != row_bytes:
                    raise LogFormatError(
                        f"array data ends at scan {index} of {self.n_scans}",
                        path=self.path,
                        field=key,
                    )
                yield np.frombuffer(data, dtype=header.dtype).reshape(row_shape)

    def _is_per_scan(self, key: str, shape: tuple[int, ...]) -> bool:
        if self.headers["ranges"].shape == (self.n_beams,):  # a single scan: no row axis
            return False
        return (
            len(shape) >= 1
            and shape[0] == self.n_scans
            and (key not in _POSE_KEYS or len(shape) == 2)
        )

    def _load(self, archive: zipfile.ZipFile, key: str) -> np.ndarray:
        try:
            with archive.open(f"{key}.npy") as fh:
                return np.lib.format.read_array(fh, allow_pickle=False)
        except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
            raise LogFormatError(f"unreadable array ({exc})", path=self.path, field=key) from None

    def _scan(self, index: int, row: dict[str, np.ndarray]) -> Scan:
        ranges = np.asarray(row["ranges"], dtype=np.float64)
        if "valid" in row:
            ranges = np.where(row["valid"] != 0, ranges, np.nan)
        stamp = _first_present(row, _TIMESTAMP_KEYS)
        pose = _first_present(row, _POSE_KEYS)
        pose_ok = pose is not None and bool(np.isfinite(pose).all())
        scalars = {k: float(row[k]) if k in row else _DEFAULTS[k] for k in _SCALAR_KEYS}
        try:
            return Scan(
                ranges,
                timestamp=None if stamp is None or np.isnan(stamp) else float(stamp),
                intensities=row.get("intensities"),
                pose=tuple(float(v) for v in pose) if pose_ok else None,  # type: ignore[union-attr]
                **scalars,
            )
        except ValueError as exc:
            raise LogFormatError(
                f"scan {index}: {exc}", path=self.path, field=str(exc).split(" ", 1)[0]
            ) from None


def _first_present(row: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray | None:
    for key in keys:
        if key in row:
            return row[key]
    return None
