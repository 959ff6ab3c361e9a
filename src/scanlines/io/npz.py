"""Stacks of scans in a numpy ``.npz`` archive.

Keys
----
``ranges``
    ``S x N`` (``S`` scans of ``N`` beams) or ``N`` (one scan), metres.
``angle_min``, ``angle_increment``
    Radians; a scalar or one value per scan (shape ``S``). Required.
``range_min``, ``range_max``
    Optional, scalar or per scan (default 0 and infinity). Without ``range_max`` (and
    without ``valid``), a largest range held by at least 1 % of all beams is taken for a
    no-return code (the SICK LMS writes 81.83 m, say), not a wall: those beams read as no
    return, and :attr:`NpzReader.notes` says so. A ``range_max`` key decides instead.
    The scans' ``range_max`` is then the float32 just below the code
    (:func:`no_return_limit`; extraction compares at float32 precision), so every path
    that reads the archive (``run``, ``extract``, ``open_log``, the viewer) reads those
    beams as no return, a single scan (``ranges`` of shape ``N``) as a stack.
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
size. Opening the archive reads the arrays through once to check their CRCs
(damaged data is an error before any scan is read, not a wrong scan). Only
Fortran-ordered arrays fall back to loading the whole key. Object arrays
(pickles) are refused; so are arrays of strings, complex numbers or records.
"""

from __future__ import annotations

import math
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from scanlines.errors import NO_SUCH_FILE, LogFormatError, ParameterError, describe
from scanlines.io.base import (
    DEFAULT_MAX_BEAMS,
    DEFAULT_MAX_RECORD_BYTES,
    ErrorPolicy,
    LogReader,
)
from scanlines.scan import Scan

__all__ = ["NpzReader"]

_PER_BEAM_KEYS = ("ranges", "valid", "intensities")
_TIMESTAMP_KEYS = ("timestamps", "timestamp")
_POSE_KEYS = ("poses", "pose", "odom_pose")
_SCALAR_KEYS = ("angle_min", "angle_increment", "range_min", "range_max")
_DEFAULTS = {"range_min": 0.0, "range_max": math.inf}
#: Without ``range_max``: the share of all beams at the largest range that makes it a
#: no-return code.
NO_RETURN_SHARE = 0.01


#: Largest ratio of uncompressed to compressed size deflate can reach (about 1032);
#: a zip member claiming more is damaged.
_MAX_DEFLATE_RATIO = 1100


class _NpyHeader:
    """Shape and dtype of one ``.npy`` member, read without loading its data."""

    def __init__(
        self, shape: tuple[int, ...], dtype: np.dtype, fortran: bool, data_offset: int
    ) -> None:
        self.shape = shape
        self.dtype = dtype
        self.fortran = fortran
        self.data_offset = data_offset

    @property
    def data_bytes(self) -> int:
        return math.prod(self.shape) * self.dtype.itemsize


def _read_header(fh: IO[bytes]) -> _NpyHeader:
    version = np.lib.format.read_magic(fh)
    if version == (1, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
    else:
        shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
    return _NpyHeader(tuple(shape), np.dtype(dtype), bool(fortran), fh.tell())


class NpzReader(LogReader):
    """Stream the scans of an ``.npz`` stack (see the module docstring for the keys).

    Parameters
    ----------
    path:
        The archive.
    on_error:
        ``"fail"`` or ``"skip"`` scans whose values are unusable (e.g. a zero
        ``angle_increment`` in one row).
    range_max:
        Every scan's largest valid range in metres, whatever the archive holds (no
        no-return code is then looked for); ``None``: the archive's.
    max_beams, max_record_bytes:
        Limits of one record (:mod:`scanlines.io.base`).

    Raises
    ------
    LogFormatError
        When the archive cannot be opened, ``ranges`` or an angle key is
        missing, or a key's shape does not match ``ranges``.
    """

    format_name = "npz"

    def __init__(
        self,
        path: str | Path,
        *,
        range_max: float | None = None,
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        super().__init__(
            path, on_error=on_error, max_beams=max_beams, max_record_bytes=max_record_bytes
        )
        if range_max is not None and not range_max > 0.0:
            raise ParameterError(f"range_max must be positive, got {range_max!r}")
        #: The ``range_max`` option: every scan's, whatever the archive holds (else None).
        self.range_max = None if range_max is None else float(range_max)
        self.headers = self._read_headers()
        self.n_scans, self.n_beams = self._check_layout()
        self._verify_data()
        #: Without ``range_max``: the no-return code found in ``ranges`` (else None).
        self.no_return_code: float | None = None
        self._code_beams = 0
        if (
            self.range_max is None
            and "range_max" not in self.headers
            and "valid" not in self.headers
        ):
            self.no_return_code, self._code_beams = self._find_no_return_code()

    def _find_no_return_code(self) -> tuple[float | None, int]:
        """The largest finite range, when at least :data:`NO_RETURN_SHARE` of all beams
        hold exactly it (a saturation code, not a measurement); and how many do."""
        largest = LargestRange()
        with self._open_zip() as archive:
            rows = self._rows(archive, "ranges")
            for _ in range(self.n_scans):
                largest.add(next(rows))
            rows.close()
        return largest.no_return_code()

    @property
    def notes(self) -> list[str]:
        """The no-return code read as no return, if one was found."""
        if self.no_return_code is None:
            return []
        total = self.n_scans * self.n_beams
        decides = "a range_max key in the archive"
        note = no_return_note(
            self.no_return_code, self._code_beams, total, "no range_max key", decides
        )
        return [note]

    # -- layout ---------------------------------------------------------------------------

    def _open_zip(self) -> zipfile.ZipFile:
        try:
            return zipfile.ZipFile(self.path)
        except FileNotFoundError:
            raise LogFormatError(NO_SUCH_FILE, path=self.path) from None
        except Exception as exc:  # zipfile raises several types on a damaged directory
            raise LogFormatError(
                f"not a readable .npz archive ({describe(exc)})", path=self.path
            ) from None

    def _read_headers(self) -> dict[str, _NpyHeader]:
        headers: dict[str, _NpyHeader] = {}
        with self._open_zip() as archive:
            for member in archive.infolist():
                if not member.filename.endswith(".npy"):
                    continue
                key = member.filename[:-4]
                try:
                    with archive.open(member) as fh:
                        headers[key] = _read_header(fh)
                except Exception as exc:  # numpy's header parser raises many types
                    raise LogFormatError(
                        f"unreadable array header ({describe(exc)})", path=self.path, field=key
                    ) from None
                _check_size(headers[key], member, self.path, key)
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
        if n_beams > self.max_beams:
            self._check_beams(n_beams, None)
        for key in self._used_keys():
            if self.headers[key].dtype.kind not in "biuf" or self.headers[key].dtype.names:
                raise LogFormatError(
                    f"must hold real numbers, got dtype {self.headers[key].dtype}",
                    path=self.path,
                    field=key,
                )
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

    def _verify_data(self) -> None:
        """Read the used arrays through once so that zipfile checks their CRCs: a damaged
        byte would otherwise be found only after the scans before it were read, and the
        damaged scan itself cannot be told from a good one."""
        with self._open_zip() as archive:
            for key in self._used_keys():
                try:
                    with archive.open(f"{key}.npy") as fh:
                        while fh.read(1 << 20):
                            pass
                except Exception as exc:  # zipfile/zlib errors on damaged data
                    raise LogFormatError(
                        f"the array data is damaged ({describe(exc)})", path=self.path, field=key
                    ) from None

    def _used_keys(self) -> list[str]:
        keys = [k for k in (*_PER_BEAM_KEYS, *_SCALAR_KEYS) if k in self.headers]
        for group in (_TIMESTAMP_KEYS, _POSE_KEYS):
            keys += [k for k in group if k in self.headers][:1]
        return keys

    @property
    def scans_in_file(self) -> int:
        return self.n_scans

    def info(self) -> dict[str, Any]:
        """Metadata known from the array headers: scan and beam counts, keys used and ignored."""
        used = self._used_keys()
        return {
            **super().info(),
            "scans_in_file": self.n_scans,
            "beams": self.n_beams,
            "keys": used,
            "ignored_keys": sorted(set(self.headers) - set(used)),
            **({"no_return_code": self.no_return_code} if self.no_return_code else {}),
        }

    # -- streaming ------------------------------------------------------------------------

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        with self._open_zip() as archive:
            streams = {key: self._rows(archive, key) for key in self._used_keys()}
            try:
                for index in range(self.n_scans):
                    try:
                        row = {key: next(stream) for key, stream in streams.items()}
                    except LogFormatError as error:  # the data ends or is damaged here
                        self._bad_record(error, count=self.n_scans - index)
                        return
                    try:
                        scan = self._scan(index, row)
                    except LogFormatError as error:
                        self._bad_record(error)
                        continue
                    self.counts["scan"] += 1
                    yield index, scan
                for key, stream in streams.items():
                    self._finish(stream, key)
            finally:
                for stream in streams.values():
                    stream.close()

    def _finish(self, stream: Iterator[np.ndarray], key: str) -> None:
        """Read a key's stream to its end, where zipfile checks the data's CRC: damage found
        only there makes the file as a whole an error (its rows were already read)."""
        for _ in stream:
            return  # a repeated value: nothing left to check

    def _rows(self, archive: zipfile.ZipFile, key: str) -> Iterator[np.ndarray]:
        """One row per scan of ``key``; a scalar (or 1-scan) array is repeated. Damaged
        data is a LogFormatError naming the key and the scan."""
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
        index = 0
        try:
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
                fh.read()  # to the end, where zipfile checks the CRC
        except LogFormatError:
            raise
        except Exception as exc:  # zipfile/zlib errors on damaged data
            raise LogFormatError(
                f"the array data is damaged at scan {index} ({describe(exc)})",
                path=self.path,
                field=key,
            ) from None

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
        except Exception as exc:  # zipfile/zlib/numpy errors on damaged data
            raise LogFormatError(
                f"unreadable array ({describe(exc)})", path=self.path, field=key
            ) from None

    def _scan(self, index: int, row: dict[str, np.ndarray]) -> Scan:
        ranges = np.asarray(row["ranges"], dtype=np.float64)
        if "valid" in row:
            ranges = np.where(row["valid"] != 0, ranges, np.nan)
        stamp = _first_present(row, _TIMESTAMP_KEYS)
        pose = _first_present(row, _POSE_KEYS)
        pose_ok = pose is not None and bool(np.isfinite(pose).all())
        scalars = {k: float(row[k]) if k in row else _DEFAULTS[k] for k in _SCALAR_KEYS}
        if self.no_return_code is not None:
            scalars["range_max"] = no_return_limit(self.no_return_code)
        if self.range_max is not None:
            scalars["range_max"] = self.range_max
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


class LargestRange:
    """The largest finite range of a log's rows and how many beams hold exactly it: a
    no-return code (the SICK 81.83 m) when they are at least :data:`NO_RETURN_SHARE` of all
    beams. The NPZ and CSV readers both decide by it."""

    def __init__(self) -> None:
        self.top, self.count, self.beams = -math.inf, 0, 0

    def add(self, row: Any) -> None:
        """One row of ranges (non-finite values are beams without a return)."""
        row = np.asarray(row, dtype=np.float64)
        self.beams += row.size
        finite = row[np.isfinite(row)]
        if not finite.size:
            return
        high = float(finite.max())
        if high > self.top:
            self.top, self.count = high, 0
        if high == self.top:
            self.count += int(np.count_nonzero(finite == self.top))

    def no_return_code(self) -> tuple[float | None, int]:
        """``(code, beams at it)``, or ``(None, 0)`` when the largest range is a range."""
        if self.count >= 2 and self.count >= NO_RETURN_SHARE * self.beams and self.top > 0:
            return self.top, self.count
        return None, 0


def no_return_note(code: float, beams: int, total: int, missing: str, decides: str) -> str:
    """The note of a reader that read a no-return code as no return."""
    share = beams / max(total, 1)
    return (
        f"{missing}: {beams} beams ({share:.1%}) at exactly {code:g} m, the largest "
        f"range, are read as no return (a no-return code such as the SICK 81.83 m); "
        f"{decides} decides"
    )


def no_return_limit(code: float) -> float:
    """The ``range_max`` that reads ``code`` as no return: the float32 just below it.
    Extraction takes ranges and limits at float32 precision (:class:`~scanlines.Extractor`);
    the float64 just below the code rounds to the code's own float32, and the beams at the
    code came back as returns there (two phantom walls 82 m away)."""
    return float(np.nextafter(np.float32(code), np.float32(0.0)))


def _check_size(header: _NpyHeader, member: zipfile.ZipInfo, path: Path, key: str) -> None:
    """An array whose header claims more data than its zip member holds is damaged (and
    must not be allocated)."""
    stored = member.file_size - header.data_offset
    deflated = member.compress_type != zipfile.ZIP_STORED
    if header.data_bytes > stored or (
        deflated and member.file_size > _MAX_DEFLATE_RATIO * max(member.compress_size, 1)
    ):
        raise LogFormatError(
            f"the header claims {header.data_bytes} bytes of data (shape {header.shape}, "
            f"{header.dtype}) but the archive holds {max(stored, 0)}",
            path=path,
            field=key,
        )


def _first_present(row: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray | None:
    for key in keys:
        if key in row:
            return row[key]
    return None
