"""A log's scans, read once in the background and then fetched by index.

A viewer must show scan 40,000 of a long log at once without holding the log in memory,
and the readers stream (a log is read from its start). So a background thread reads the
log once into an anonymous temporary file: per scan, a 56-byte header (sensor fields,
time, pose, record number) and the ranges as float32 (the precision extraction takes them
at, so a scan read back extracts exactly as the original). :meth:`ScanStore.scan` reads
one scan back by index. The first scans are there within milliseconds of opening; asking
for a scan the reader has not reached yet waits for it.

Memory: each scan's place in the file (8 bytes a scan: 0.8 MB for 100,000 scans) and a
cache of the last :data:`CACHED_SCANS` scans. Disk: 56 bytes a scan and four a beam, in a
file that the system deletes when the store closes or the process ends, however it ends.
"""

from __future__ import annotations

import math
import os
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError, ScanlinesError
from scanlines.reader_options import ReaderOptions
from scanlines.scan import Scan

__all__ = ["CACHED_SCANS", "ScanStore"]

CACHED_SCANS = 64

_HEADER = np.dtype([
    ("record", np.int64), ("timestamp", np.float64), ("pose", np.float64, 3),
    ("angle_min", np.float32), ("angle_increment", np.float32),
    ("range_min", np.float32), ("range_max", np.float32),
])  # fmt: skip


class ScanStore:
    """The scans of the log at ``path``, by index (0 = the first scan read).

    Parameters
    ----------
    path:
        Any log :func:`scanlines.io.open_log` reads.
    reader_options:
        Options of its reader (``on_error``, ``topic``, ``fov``...).
    spool_dir:
        Folder of the temporary ranges file (default: the system's temporary folder).
    """

    def __init__(
        self, path: str | Path, reader_options: ReaderOptions | Mapping[str, Any] | None = None,
        *, spool_dir: str | Path | None = None,
    ) -> None:  # fmt: skip
        from scanlines.io import open_log

        self.path = Path(path)
        self.reader_options = ReaderOptions.of(reader_options)
        self.reader = open_log(self.path, options=self.reader_options)  # bad options fail here
        self.format_name = self.reader.format_name
        self.reader_info: dict[str, Any] = {}
        self.error: str | None = None
        # open for the store's life, closed by close(): no context manager fits
        self._file = tempfile.TemporaryFile(prefix="scanlines-view-", dir=spool_dir)  # noqa: SIM115
        self._offsets = np.zeros(1024, np.int64)  # scan k: bytes offsets[k] to offsets[k + 1]
        self._count = 0
        self._written = 0
        self._finished = False
        self._stop = False
        self._hold_at: int | None = None
        self._resumed = threading.Event()
        self._cache: OrderedDict[int, Scan] = OrderedDict()
        self._cache_lock = threading.Lock()
        self._changed = threading.Condition()
        self._thread = threading.Thread(target=self._read_log, name="scan-store", daemon=True)
        self._thread.start()

    # -- what has been read ---------------------------------------------------------------

    @property
    def count(self) -> int:
        """Scans read so far (all of them once :attr:`finished`)."""
        return self._count

    @property
    def finished(self) -> bool:
        """Whether the whole log has been read (or reading stopped at an error)."""
        return self._finished

    @property
    def with_pose(self) -> bool:
        """Whether the first scan has a pose (logs give poses for all scans or none)."""
        return self._count > 0 and not math.isnan(float(self._read_header(0)["pose"][0]))

    def hold(self, after: int) -> None:
        """Pause reading once ``after`` scans are read, until :meth:`resume` (or a scan
        past them is asked for): the first frame is not slowed by the read of a long log."""
        self._hold_at = after

    def resume(self) -> None:
        """Go on reading after :meth:`hold`."""
        self._resumed.set()

    def wait_for(self, count: int, timeout: float | None = None) -> bool:
        """Wait until ``count`` scans are read or the log ends; whether they were."""
        with self._changed:
            self._changed.wait_for(lambda: self._count >= count or self._finished, timeout)
        return self._count >= count

    def record(self, index: int) -> int:
        """The record number in the log of scan ``index`` (read already)."""
        return int(self._read_header(index)["record"])

    # -- one scan -------------------------------------------------------------------------

    def scan(self, index: int, *, timeout: float = 30.0) -> Scan:
        """Scan ``index``, waiting (up to ``timeout`` seconds) for the reader to reach it.

        Raises
        ------
        ParameterError
            ``index`` is not a scan of the log (the message says how many there are).
        """
        if isinstance(index, bool) or not isinstance(index, int) or index < 0:
            raise ParameterError(f"scan index must be an integer >= 0, got {index!r}")
        with self._cache_lock:
            cached = self._cache.get(index)
            if cached is not None:
                self._cache.move_to_end(index)
                return cached
        if index >= self._count:
            self.resume()
        if not self.wait_for(index + 1, timeout):
            raise ParameterError(self._out_of_range(index))
        scan = self._read_back(index)
        with self._cache_lock:
            self._cache[index] = scan
            while len(self._cache) > CACHED_SCANS:
                self._cache.popitem(last=False)
        return scan

    def _out_of_range(self, index: int) -> str:
        if not self._finished:
            return f"scan {index} is not read yet ({self._count} scans so far); try again"
        problem = f" (reading stopped: {self.error})" if self.error else ""
        return f"scan {index} is out of range: {self.path.name} has {self._count} scans{problem}"

    def _read_header(self, index: int) -> np.void:
        data = os.pread(self._file.fileno(), _HEADER.itemsize, int(self._offsets[index]))
        return np.frombuffer(data, _HEADER)[0]

    def _read_back(self, index: int) -> Scan:
        offsets = self._offsets
        start, end = int(offsets[index]), int(offsets[index + 1])
        data = os.pread(self._file.fileno(), end - start, start)
        header = np.frombuffer(data[: _HEADER.itemsize], _HEADER)[0]
        ranges = np.frombuffer(data[_HEADER.itemsize :], np.float32).astype(np.float64)
        pose, timestamp = header["pose"].copy(), float(header["timestamp"])
        return Scan(
            ranges, float(header["angle_min"]), float(header["angle_increment"]),
            float(header["range_min"]), float(header["range_max"]),
            timestamp=None if math.isnan(timestamp) else timestamp,
            pose=None if math.isnan(pose[0]) else pose,
        )  # fmt: skip

    # -- the background read --------------------------------------------------------------

    def _read_log(self) -> None:
        try:
            with self.reader:
                for record, scan in self.reader.enumerate():
                    if self._stop:
                        return
                    self._append(record, scan)
                    if self._count == self._hold_at:
                        self._resumed.wait()
        except ScanlinesError as error:
            self.error = str(error)
        except OSError as error:
            self.error = f"{self.path}: {error}"
        finally:
            self.reader_info = self.reader.info()
            with self._changed:
                self._finished = True
                self._changed.notify_all()

    def _append(self, record: int, scan: Scan) -> None:
        header = np.zeros(1, _HEADER)
        header["record"] = record
        header["timestamp"] = math.nan if scan.timestamp is None else scan.timestamp
        header["pose"] = (math.nan,) * 3 if scan.pose is None else scan.pose
        header["angle_min"], header["angle_increment"] = scan.angle_min, scan.angle_increment
        header["range_min"], header["range_max"] = scan.range_min, scan.range_max
        data = header.tobytes() + np.asarray(scan.ranges, np.float32).tobytes()
        self._file.write(data)
        self._file.flush()
        if self._count + 2 > len(self._offsets):
            self._offsets = np.resize(self._offsets, 2 * len(self._offsets))
        self._written += len(data)
        self._offsets[self._count + 1] = self._written  # before the count: readers see it
        with self._changed:
            self._count += 1
            self._changed.notify_all()

    def close(self) -> None:
        """Stop reading and delete the temporary file."""
        self._stop = True
        self._resumed.set()
        self._thread.join(timeout=5)
        self._file.close()

    def __enter__(self) -> ScanStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
