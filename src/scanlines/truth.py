"""What the truth of a simulated scan is: the types scoring reads.

:class:`Truth` holds the exact breakpoints, corners and segments of one scan and what
happened to every beam (:class:`BeamStatus`); :class:`TrueSegments` its true segments.
Scoring (:mod:`scanlines.evaluation.metrics`) reads these types only; the simulator
(:mod:`scanlines.sim.truth`) computes them and states the conventions (what counts as
a breakpoint, a corner, a segment). Only numpy is needed: this module does not import
the simulator.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

__all__ = ["BeamStatus", "TrueSegments", "Truth"]


class BeamStatus(IntEnum):
    """What happened to one simulated beam."""

    HIT = 0
    """A valid return of the true surface (with range noise)."""
    NO_HIT = 1
    """No surface along the beam: no return."""
    DROPOUT = 2
    """The beam hit a surface but the sensor returned nothing (random dropout)."""
    OUTLIER = 3
    """A spurious short return that belongs to no surface."""
    MIXED = 4
    """A mixed pixel: a return between two surfaces at a depth discontinuity."""
    OUT_OF_RANGE = 5
    """The measured range fell outside ``[range_min, range_max]``: no return."""


@dataclass(frozen=True, eq=False)
class TrueSegments:
    """The true segments of one scan, as parallel arrays (one row per segment).

    Attributes
    ----------
    first, last:
        Inclusive beam indices (``first > last`` only across the seam).
    edge:
        Edge id of the world edge the segment lies on.
    n_returns:
        True returns in the segment.
    rho, alpha:
        Hesse normal form of the true edge line in the sensor frame.
    start, end:
        ``M x 2`` exact hit points of the first and last beam (sensor frame).
    """

    first: np.ndarray
    last: np.ndarray
    edge: np.ndarray
    n_returns: np.ndarray
    rho: np.ndarray
    alpha: np.ndarray
    start: np.ndarray
    end: np.ndarray

    def __len__(self) -> int:
        return len(self.first)

    @property
    def lines(self) -> np.ndarray:
        """``M x 7`` rows like :attr:`scanlines.Extraction.lines` (rms is 0)."""
        return np.column_stack(
            (self.rho, self.alpha, self.start, self.end, np.zeros(len(self)))
        ).reshape(-1, 7)


@dataclass(frozen=True, eq=False)
class Truth:
    """Ground truth of one simulated scan (the rules: :mod:`scanlines.sim.truth`).

    Attributes
    ----------
    n_beams:
        Number of beams.
    full_circle:
        Whether the scan closes the circle (its seam is crossed like any pair).
    pose:
        Sensor pose ``(x, y, theta)`` in the world frame.
    edge:
        Edge each beam's ray hits (at any distance), ``-1`` for none.
    true_ranges:
        Exact range to that edge, ``inf`` for none.
    hit_points:
        ``N x 2`` exact hit points in the sensor frame (NaN for none).
    incidence:
        Angle in radians between each beam and the normal of the surface it hits
        (0 = head-on, near pi/2 = grazing; NaN for none).
    on_curve:
        Beams whose ray hits a curved shape (not a line).
    status:
        :class:`BeamStatus` code of each beam.
    breakpoints:
        Sorted beam indices of the true breakpoints.
    breakpoint_runs:
        ``B x 2``: true returns in the run before and after each breakpoint.
    corners:
        Sorted beam indices of the true corners.
    corner_points:
        ``C x 2`` corner vertices in the sensor frame.
    corner_runs:
        ``C x 2``: true returns in the run before and after each corner.
    segments:
        The true segments.
    breakpoint_dont_care, corner_dont_care:
        Masks over :attr:`breakpoints` and :attr:`corners`: events no extractor can be
        asked to find (a junction of touching surfaces, a depth step or a turn the
        range noise hides; the rules: :mod:`scanlines.sim.truth`). Scoring treats them
        like uncertain hand labels when
        :attr:`~scanlines.evaluation.scores.Tolerances.truth_dont_care` is on: a
        detection matched to one is neither a true nor a false positive, missing one is
        no false negative. ``None`` (the default) means none.
    """

    n_beams: int
    full_circle: bool
    pose: tuple[float, float, float]
    edge: np.ndarray
    true_ranges: np.ndarray
    hit_points: np.ndarray
    incidence: np.ndarray
    on_curve: np.ndarray
    status: np.ndarray
    breakpoints: np.ndarray
    breakpoint_runs: np.ndarray
    corners: np.ndarray
    corner_points: np.ndarray
    corner_runs: np.ndarray
    segments: TrueSegments
    breakpoint_dont_care: np.ndarray | None = None
    corner_dont_care: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name, events in (
            ("breakpoint_dont_care", self.breakpoints),
            ("corner_dont_care", self.corners),
        ):
            mask = getattr(self, name)
            mask = np.zeros(len(events), bool) if mask is None else np.asarray(mask, bool)
            if mask.shape != (len(events),):
                raise ValueError(f"{name} must have one entry per event, got {mask.shape}")
            if mask.flags.writeable:
                mask = mask.copy()
                mask.setflags(write=False)
            object.__setattr__(self, name, mask)

    @property
    def dont_care_breakpoints(self) -> np.ndarray:
        """Beam indices of the don't-care breakpoints (see :attr:`breakpoint_dont_care`)."""
        return self.breakpoints[self.breakpoint_dont_care]

    @property
    def true_return(self) -> np.ndarray:
        """Beams whose measured range is a return of the surface they hit."""
        return self.status == BeamStatus.HIT

    @property
    def outliers(self) -> np.ndarray:
        """Beam indices of injected outliers (spurious short returns)."""
        return np.flatnonzero(self.status == BeamStatus.OUTLIER)

    @property
    def mixed_pixels(self) -> np.ndarray:
        """Beam indices of mixed pixels (returns between two surfaces)."""
        return np.flatnonzero(self.status == BeamStatus.MIXED)

    @property
    def dropouts(self) -> np.ndarray:
        """Beam indices of random dropouts."""
        return np.flatnonzero(self.status == BeamStatus.DROPOUT)
