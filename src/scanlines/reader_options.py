"""The options of every log reader, as one type."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from scanlines.errors import ParameterError

__all__ = ["SCANS_HELP", "ReaderOptions", "parse_scans", "select_scans"]


@dataclass(frozen=True)
class ReaderOptions:
    """Options for :func:`~scanlines.io.open_log`. ``None`` keeps the reader's default.

    Each reader takes some of them (:func:`~scanlines.io.reader_option_names`). Giving
    one the log's reader does not take is an error. Angles are in radians, lengths in
    metres. The readers' modules document each option.
    """

    message: str | None = None  # CARMEN: the laser message to read
    fov: float | None = None  # CARMEN, CoreSLAM: field of view
    angle_convention: str | None = None  # CARMEN: "step" or "linspace"
    max_range: float | None = None  # CARMEN
    range_min: float | None = None  # CARMEN, CoreSLAM, CSV
    range_max: float | None = None  # CARMEN (as max_range), CoreSLAM, CSV, NPZ
    pose: str | None = None  # CARMEN: "laser" or "robot"
    mounting: Sequence[float] | None = None  # CARMEN: the laser's (x, y, theta) on the robot
    timestamp: str | None = None  # CARMEN: "logger" or "ipc"
    topic: str | None = None  # bags
    beams: int | None = None  # CoreSLAM
    angle_min: float | None = None  # CSV
    angle_increment: float | None = None  # CSV
    timestamp_column: bool | None = None  # CSV
    on_error: str | None = None  # every reader: "fail" or "skip"
    max_beams: int | None = None  # every reader
    max_record_bytes: int | None = None  # every reader

    @classmethod
    def of(cls, options: ReaderOptions | Mapping[str, Any] | None) -> ReaderOptions:
        """``options`` as :class:`ReaderOptions`: a mapping of option names, or none."""
        if options is None:
            return cls()
        if isinstance(options, ReaderOptions):
            return options
        unknown = sorted(set(options) - {field.name for field in dataclasses.fields(cls)})
        if unknown:
            raise ParameterError(
                f"unknown reader option(s) {', '.join(unknown)}; options: {', '.join(cls.names())}"
            )
        return cls(**options)

    @classmethod
    def names(cls) -> list[str]:
        """Every option's name."""
        return [field.name for field in dataclasses.fields(cls)]

    def given(self) -> dict[str, Any]:
        """The options that were set, as keywords for a reader."""
        values = ((name, getattr(self, name)) for name in self.names())
        return {name: value for name, value in values if value is not None}

    def but(self, **changes: Any) -> ReaderOptions:
        """These options with ``changes``."""
        return dataclasses.replace(self, **changes)


#: The one grammar of ``--scans`` in every command, for its help.
SCANS_HELP = (
    "Scans of the log: N the first N, START:STOP[:STEP] a Python slice of scan indices "
    "(100:200 scans 100-199, 7:8 scan 7 alone, ::10 every 10th)."
)


def parse_scans(text: str | int | None) -> slice:
    """``--scans`` as a slice of scan indices, the same in every command: ``"N"`` the
    first N scans, ``"START:STOP[:STEP]"`` as in Python (``"100:200"``, ``":50"``,
    ``"10:"``, ``"::5"``); ``None``, ``""`` or ``":"`` every scan.

    Raises
    ------
    ParameterError
        For anything else, a negative index (the log streams: its length is not known), a
        step below 1 or a selection that holds no scan.
    """
    if text is None or str(text).strip() in ("", ":"):
        return slice(None)
    text = str(text).strip()
    parts = text.split(":")
    if len(parts) > 3:
        raise ParameterError(f"--scans takes N or START:STOP[:STEP], got {text!r}")
    try:
        values = [int(p) if p.strip() else None for p in parts]
    except ValueError:
        raise ParameterError(
            f"--scans takes N or START:STOP[:STEP] (integers), got {text!r}"
        ) from None
    if any(v is not None and v < 0 for v in values):
        raise ParameterError(f"--scans takes non-negative indices (the log streams), got {text!r}")
    if len(values) == 1:
        values = [0, values[0]]
    if len(values) == 3 and values[2] is not None and values[2] < 1:
        raise ParameterError(f"--scans step must be at least 1, got {text!r}")
    start, stop = values[0] or 0, values[1]
    if stop is not None and stop <= start:
        raise ParameterError(f"--scans {text} selects no scan (STOP must exceed START)")
    return slice(*values)


def select_scans(indexed: Iterable[tuple[int, Any]], scans: slice) -> Iterator[tuple[int, Any]]:
    """The ``(index, scan)`` pairs whose index falls in ``scans``, stopping past its end."""
    start = scans.start or 0
    step = scans.step or 1
    for index, scan in indexed:
        if scans.stop is not None and index >= scans.stop:
            break
        if index >= start and (index - start) % step == 0:
            yield index, scan
