"""The options of every log reader, as one type."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from scanlines.errors import ParameterError

__all__ = ["ReaderOptions"]


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
    range_max: float | None = None  # CoreSLAM, CSV
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
