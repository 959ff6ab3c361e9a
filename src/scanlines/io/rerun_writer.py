"""Writing extraction results as a Rerun recording (``.rrd``).

:func:`scanlines.io.open_writer` picks this writer for ``*.rrd``. The Rerun SDK is
imported only here: ``pip install "scanlines[rerun]"`` brings it. Open the file with
``rerun x.rrd``.

Timelines, per scan:

* ``scan``: sequence, the scan's record index in the log;
* ``time``: timestamp, the scan's time in seconds as the log gives it (logs with
  times relative to their start show as dates in January 1970); scans without a
  time are not on it.

Entities, in the sensor frame or, with ``frame="world"``, the log's world frame:

=====================  ============  ==================================================
``scan/returns``       Points2D      beams with a return (grey)
``scan/segments``      LineStrips2D  one strip per segment, start to end; segment ``k``
                                     gets the same colour in every scan
``scan/breakpoints``   Points2D      breakpoint beams (red)
``scan/corners``       Points2D      corner beams (blue)
``scan/outliers``      Points2D      beams rejected as isolated noise (orange)
=====================  ============  ==================================================

Every entity is logged for every scan, empty when the scan has none of it, so nothing
of an earlier scan lingers; the colours and radii of the points are logged once, static.
The recording's application id is ``scanlines``, its name the output's stem; its
wall-clock ``log_time`` timeline is left out.

The SDK saves into a pipe (a FIFO in a private temporary folder) and a thread of this
process copies it to the temporary output (:class:`_Copier`): the SDK's own file sink,
on a write error (a full disk), logs it and stops writing, and its ``flush`` then waits
for ever. Here the error is kept and raised by the next :meth:`RerunWriter.write` (or
by ``close``) as one :class:`~scanlines.outputs.OutputError` naming the output, and the
rest of the stream is read and dropped, so the SDK never waits.
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import shutil
import tempfile
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.extraction import END_X, END_Y, START_X, START_Y
from scanlines.io.writers import Frame, ResultWriter, ScanFeatures
from scanlines.outputs import discard, temp_path, umask

__all__ = ["RerunWriter", "require_rerun", "segment_colors"]

#: Points2D entity -> (RGB colour, radius in metres).
_POINT_STYLES = {
    "returns": ((150, 150, 150), 0.02),
    "outliers": ((255, 150, 0), 0.03),
    "breakpoints": ((230, 25, 25), 0.06),
    "corners": ((25, 75, 255), 0.08),
}
_SEGMENT_RADIUS = 0.015


def require_rerun() -> Any:
    """The ``rerun`` module, or a one-line error naming the extra."""
    try:
        import rerun
    except ImportError:
        raise ParameterError(
            'Rerun output needs the Rerun SDK: pip install "scanlines[rerun]"'
        ) from None
    return rerun


@functools.cache
def segment_colors(count: int) -> np.ndarray:
    """Colours of segments ``0 .. count - 1`` as packed ``0xRRGGBBAA`` (uint32, Rerun's
    fastest input; read-only, cached): hues a golden ratio apart, so neighbours differ
    and segment ``k`` has the same colour in every scan."""
    hue = (np.arange(count) * 0.618033988749895) % 1.0
    k = (np.array([5.0, 3.0, 1.0]) + 6.0 * hue[:, None]) % 6.0  # HSV -> RGB, s 0.8, v 0.95
    rgb = 0.95 * (1.0 - 0.8 * np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0))
    r, g, b = np.round(255.0 * rgb).astype(np.uint32).T
    colors = (r << 24) | (g << 16) | (b << 8) | np.uint32(0xFF)
    colors.setflags(write=False)
    return colors


class RerunWriter(ResultWriter):
    """Scans and features as a Rerun recording (see the module docstring).

    Parameters
    ----------
    path:
        ``*.rrd`` file.
    meta, frame, overwrite:
        See :class:`~scanlines.io.writers.ResultWriter`.
    """

    format_name = "rerun"

    def __init__(
        self,
        path: str | Path,
        *,
        meta: Mapping[str, Any] | None = None,
        frame: Frame = "sensor",
        overwrite: bool = False,
    ) -> None:
        self._rr = require_rerun()
        super().__init__(path, meta=meta, frame=frame, overwrite=overwrite)
        if self.path.is_dir():
            raise ParameterError(f"{self.path} is a directory")
        # A stream of its own (never the global recording), saved through a pipe.
        self._stream = self._rr.RecordingStream(application_id="scanlines")
        if not self._stream.is_enabled():
            raise ParameterError(
                f"{self.path}: Rerun logging is disabled in this environment (RERUN=off?)"
            )
        self._stream.set_log_time_enabled(False)
        self._temporary_file = temp_path(self.path)
        self._copier: _Copier | None = None
        try:
            with self._naming_the_output():
                self._copier = _Copier(self._temporary_file)
            self._stream.save(self._copier.pipe)
            self._stream.send_recording_name(self.path.stem)
            for name, (color, radius) in _POINT_STYLES.items():
                style = self._rr.Points2D.from_fields(colors=color, radii=radius)
                self._stream.log(f"scan/{name}", style, static=True)
        except BaseException:
            self._abort()
            raise

    def _write(self, features: ScanFeatures) -> None:
        self._copier.check()  # type: ignore[union-attr]  # a write error so far
        rr, stream, timestamp = self._rr, self._stream, features.scan.timestamp
        stream.set_time("scan", sequence=features.index)
        if timestamp is not None and math.isfinite(timestamp):
            stream.set_time("time", timestamp=timestamp)
        else:
            stream.disable_timeline("time")
        lines = features.extraction.lines
        strips = lines[:, [START_X, START_Y, END_X, END_Y]].reshape(-1, 2, 2)
        stream.log(
            "scan/segments",
            rr.LineStrips2D(strips, radii=_SEGMENT_RADIUS, colors=segment_colors(len(strips))),
        )
        stream.log("scan/returns", rr.Points2D(features.return_points))
        stream.log("scan/outliers", rr.Points2D(features.outlier_points))
        stream.log("scan/breakpoints", rr.Points2D(features.breakpoint_points))
        stream.log("scan/corners", rr.Points2D(features.corner_points))

    @property
    def _temporary(self) -> Path:
        return self._temporary_file

    def _finish(self) -> None:
        self._stream.flush()  # waits until every batch has reached the pipe
        self._stream.disconnect()  # closes the pipe (with the recording's footer)
        self._copier.close()  # type: ignore[union-attr]  # raises a write error
        os.chmod(self._temporary_file, 0o666 & ~umask())

    def _abort(self) -> None:
        with contextlib.suppress(Exception):
            self._stream.disconnect()
        if self._copier is not None:
            with contextlib.suppress(Exception):  # the write error, raised already
                self._copier.close()
        discard(self._temporary_file)


class _Copier:
    """A pipe the Rerun SDK saves into, copied by a thread to ``target`` (created here).

    A write error (a full disk, a file size limit) is kept (:meth:`check` and
    :meth:`close` raise it) and the rest of the stream read and dropped: the SDK never
    waits on a full pipe.
    """

    def __init__(self, target: Path) -> None:
        self._folder = Path(tempfile.mkdtemp(prefix="scanlines-rrd-"))
        self._file = None
        self._descriptors: list[int] = []
        try:
            #: The pipe to hand to the SDK's ``save``.
            self.pipe = self._folder / "recording.rrd"
            os.mkfifo(self.pipe, 0o600)
            self._read = os.open(self.pipe, os.O_RDONLY | os.O_NONBLOCK)
            self._descriptors.append(self._read)
            # A writer of our own until the end: no end of stream before the SDK's opens.
            self._keep_open = os.open(self.pipe, os.O_WRONLY)
            self._descriptors.append(self._keep_open)
            os.set_blocking(self._read, True)
            self._file = open(target, "xb")  # noqa: SIM115 - closed by close()
        except BaseException:
            self._release()
            raise
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._copy, name="rrd copier", daemon=True)
        self._thread.start()

    def _copy(self) -> None:
        while data := os.read(self._read, 1 << 16):
            if self.error is None:
                try:
                    self._file.write(data)  # type: ignore[union-attr]
                except BaseException as error:  # kept for the writer, which raises it
                    self.error = error

    def check(self) -> None:
        """Raise the write error met so far, if any."""
        if self.error is not None:
            raise self.error

    def close(self) -> None:
        """After the SDK closed its end: copy the rest, write the file through to the
        disk and close it; raise the write error met, if any."""
        if self._keep_open in self._descriptors:
            self._descriptors.remove(self._keep_open)
            os.close(self._keep_open)
            self._thread.join()
        file, self._file = self._file, None
        try:
            if file is not None:
                try:
                    self.check()
                    file.flush()
                    os.fsync(file.fileno())
                finally:
                    file.close()
            self.check()
        finally:
            self._release()

    def _release(self) -> None:
        for descriptor in self._descriptors:
            os.close(descriptor)
        self._descriptors.clear()
        if self._file is not None:
            with contextlib.suppress(OSError):
                self._file.close()
            self._file = None
        shutil.rmtree(self._folder, ignore_errors=True)
