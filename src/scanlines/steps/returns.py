"""The valid returns of a scan, the bundle every step works on.

Steps work on *positions*: the valid returns in beam order, with the beams that
have no return left out. ``returns.index[p]`` maps a position back to its beam.
Points are in the scan's local frame (beam 0 at bearing 0), which makes every
decision independent of ``angle_min``. For a full-circle scan the returns may be
rotated so that they start after a real gap, which lets a cluster run across the
seam (then ``index`` wraps from ``n_beams - 1`` to ``0`` inside the returns).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from scanlines import _core

__all__ = [
    "MAX_BRIDGED_GAP",
    "Returns",
    "beam_gaps",
    "valid_returns",
    "without",
]

MAX_BRIDGED_GAP: int = _core.MAX_BRIDGED_GAP
"""Largest beam gap between consecutive returns that may still be one cluster
(one missing beam in between)."""


class Returns(NamedTuple):
    """The valid returns of one scan, in scan order.

    Attributes
    ----------
    index:
        Beam index of each position (int64).
    r:
        Range of each position.
    x, y:
        Point of each position in the scan's local frame (beam 0 along x).
    """

    index: np.ndarray
    r: np.ndarray
    x: np.ndarray
    y: np.ndarray


def valid_returns(ranges: np.ndarray, valid: np.ndarray, cos: np.ndarray, sin: np.ndarray):
    """:class:`Returns` of the beams marked ``valid``; ``cos, sin`` the bearing tables
    relative to beam 0."""
    index = np.flatnonzero(valid).astype(np.int64)
    r = ranges[index]
    return Returns(index, r, r * cos[index], r * sin[index])


def beam_gaps(index: np.ndarray, n_beams: int) -> np.ndarray:
    """Beams between consecutive positions (1 = adjacent beams; a rotated full circle
    wraps once)."""
    return np.diff(index) % n_beams


def without(returns: Returns, drop: np.ndarray) -> Returns:
    """``returns`` without the positions where the mask ``drop`` is True."""
    keep = np.flatnonzero(~drop)
    return Returns(*(values[keep] for values in returns))
