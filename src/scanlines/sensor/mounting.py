"""The laser's mounting on the robot, from the mountings a log records with its scans."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

#: Recorded mountings further than this from their median (metres, radians) disagree.
MOUNTING_AGREEMENT = (0.01, math.radians(0.5))
#: Share of the recorded mountings that must agree for the log to have one mounting.
MOUNTING_QUORUM = 0.9


def estimate_mounting(
    recorded: Iterable[tuple[float, float, float]],
) -> tuple[float, float, float] | None:
    """The laser's ``(x, y, theta)`` on the robot from the mountings a log records with
    its scans (:attr:`~scanlines.io.base.LogReader.recorded_mounting`): their median,
    when at least :data:`MOUNTING_QUORUM` of them lie within :data:`MOUNTING_AGREEMENT`
    of it; ``None`` when none are recorded or they disagree (no rigid mounting)."""
    samples = np.array(list(recorded), dtype=np.float64).reshape(-1, 3)
    if samples.shape[0] == 0:
        return None
    x, y = np.median(samples[:, 0]), np.median(samples[:, 1])
    reference = samples[0, 2]
    theta = math.remainder(
        reference + float(np.median(_turns(samples[:, 2], reference))), 2 * math.pi
    )
    offset = np.hypot(samples[:, 0] - x, samples[:, 1] - y)
    turn_off = np.abs(_turns(samples[:, 2], theta))
    agree = (offset <= MOUNTING_AGREEMENT[0]) & (turn_off <= MOUNTING_AGREEMENT[1])
    if agree.mean() < MOUNTING_QUORUM:
        return None
    return (float(x), float(y), float(theta))


def _turns(angles: np.ndarray, reference: float) -> np.ndarray:
    """``angles - reference`` wrapped to ``[-pi, pi)``."""
    return np.remainder(angles - reference + np.pi, 2 * np.pi) - np.pi
