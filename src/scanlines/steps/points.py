"""The valid returns of a scan as one ordered sequence.

Every step works on *sequence positions*: the valid returns in beam order, with
beams that have no return left out. ``index[p]`` maps a position back to its beam.
For a full-circle scan the sequence may be rotated so that it starts after a
real gap, which lets a cluster run across the seam (then ``index`` wraps from
``n_beams - 1`` to ``0`` inside the sequence).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Sequence", "make_sequence", "rotate"]


@dataclass(frozen=True, slots=True)
class Sequence:
    """Valid returns in scan order, in the scan's local frame (beam 0 at bearing 0).

    Attributes
    ----------
    index:
        Beam index of each position.
    r, x, y:
        Range and Cartesian coordinates of each position.
    gap:
        ``gap[p]`` = beams from position ``p`` to ``p + 1`` (1 = adjacent beams);
        length ``len(index) - 1``.
    step:
        Absolute angular increment in radians.
    n_beams:
        Beams in the scan, valid or not.
    """

    index: np.ndarray
    r: np.ndarray
    x: np.ndarray
    y: np.ndarray
    gap: np.ndarray
    step: float
    n_beams: int

    def __len__(self) -> int:
        return int(self.index.shape[0])

    def seam_gap(self) -> int:
        """Beams from the last position round the seam to the first (full circles)."""
        return int(self.index[0] + self.n_beams - self.index[-1])

    def with_points(self, x: np.ndarray, y: np.ndarray) -> Sequence:
        """The same sequence with moved points (ranges recomputed)."""
        return Sequence(self.index, np.hypot(x, y), x, y, self.gap, self.step, self.n_beams)

    def turned(self, angle: float) -> Sequence:
        """The same returns in a frame turned by ``-angle`` (points rotated by ``angle``)."""
        c, s = np.cos(angle), np.sin(angle)
        return Sequence(
            self.index,
            self.r,
            c * self.x - s * self.y,
            s * self.x + c * self.y,
            self.gap,
            self.step,
            self.n_beams,
        )

    def subset(self, keep: np.ndarray) -> Sequence:
        """The sequence without the positions where ``keep`` is False."""
        index = self.index[keep]
        return Sequence(
            index,
            self.r[keep],
            self.x[keep],
            self.y[keep],
            _gaps(index, self.n_beams),
            self.step,
            self.n_beams,
        )


def _gaps(index: np.ndarray, n_beams: int) -> np.ndarray:
    # Modulo handles a rotated full-circle sequence, where the index wraps once.
    return np.diff(index) % n_beams if n_beams else np.diff(index)


def make_sequence(
    ranges: np.ndarray, valid: np.ndarray, cos: np.ndarray, sin: np.ndarray, step: float
) -> Sequence:
    """Collect the valid returns of a scan.

    Parameters
    ----------
    ranges, valid:
        The scan's ranges and validity mask.
    cos, sin:
        Cosine and sine of each beam's bearing relative to beam 0.
    step:
        The angular increment (its sign is ignored).
    """
    index = np.flatnonzero(valid)
    r = ranges[index]
    return Sequence(
        index=index,
        r=r,
        x=r * cos[index],
        y=r * sin[index],
        gap=np.diff(index),
        step=abs(float(step)),
        n_beams=int(ranges.shape[0]),
    )


def rotate(seq: Sequence, start: int) -> Sequence:
    """Rotate a full-circle sequence so that position ``start`` comes first."""
    order = np.r_[start : len(seq), 0:start]
    index = seq.index[order]
    return Sequence(
        index,
        seq.r[order],
        seq.x[order],
        seq.y[order],
        _gaps(index, seq.n_beams),
        seq.step,
        seq.n_beams,
    )
