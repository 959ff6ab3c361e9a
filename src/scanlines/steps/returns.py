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

from scanlines._jit import kernel

__all__ = [
    "MAX_BRIDGED_GAP",
    "Returns",
    "beam_gaps",
    "rotated",
    "valid_returns",
    "without",
]

MAX_BRIDGED_GAP = 2
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


@kernel
def valid_returns(ranges, valid, cos, sin):
    """:class:`Returns` of the beams marked ``valid``; ``cos, sin`` the bearing tables
    relative to beam 0."""
    count = 0
    for i in range(valid.shape[0]):
        count += valid[i]
    index = np.empty(count, dtype=np.int64)
    r = np.empty(count)
    x = np.empty(count)
    y = np.empty(count)
    p = 0
    for i in range(valid.shape[0]):
        if valid[i]:
            index[p], r[p] = i, ranges[i]
            x[p], y[p] = ranges[i] * cos[i], ranges[i] * sin[i]
            p += 1
    return Returns(index, r, x, y)


@kernel
def beam_gaps(index, n_beams):
    """Beams between consecutive positions (1 = adjacent beams; a rotated full
    circle wraps once)."""
    gap = np.empty(max(index.shape[0] - 1, 0), dtype=np.int64)
    for p in range(gap.shape[0]):
        gap[p] = (index[p + 1] - index[p]) % n_beams
    return gap


@kernel
def rotated(returns, shift):
    """``returns`` rotated so that position ``shift`` comes first."""
    index, r, x, y = returns
    return Returns(
        np.concatenate((index[shift:], index[:shift])),
        np.concatenate((r[shift:], r[:shift])),
        np.concatenate((x[shift:], x[:shift])),
        np.concatenate((y[shift:], y[:shift])),
    )


@kernel
def without(returns, drop):
    """``returns`` without the positions where the mask ``drop`` is True."""
    keep = np.flatnonzero(~drop)
    index, r, x, y = returns
    return Returns(index[keep], r[keep], x[keep], y[keep])
