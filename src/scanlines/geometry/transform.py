"""Moving features from the sensor frame to the world frame of the log.

A pose ``(x, y, theta)`` maps a sensor-frame point ``p`` to ``R(theta) p +
(x, y)``. A line ``x cos(alpha) + y sin(alpha) = rho`` maps to ``alpha' =
alpha + theta`` and ``rho' = rho + x cos(alpha') + y sin(alpha')``, flipped to
keep ``rho' >= 0`` and ``alpha'`` in ``(-pi, pi]``; its ``(rho, alpha)``
covariance is carried through the Jacobian of that map. Beam indices
(``first``, ``last``, breakpoints, corners, outliers) do not depend on the
frame and are kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from scanlines.extraction import (
    ALPHA,
    END_X,
    END_Y,
    RHO,
    START_X,
    START_Y,
    Extraction,
)

__all__ = ["points_to_world", "to_world"]


def points_to_world(points: np.ndarray, pose: Sequence[float]) -> np.ndarray:
    """``K x 2`` sensor-frame points in the world frame (NaN rows stay NaN)."""
    x, y, theta = (float(v) for v in pose)
    c, s = math.cos(theta), math.sin(theta)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return np.column_stack((x + c * pts[:, 0] - s * pts[:, 1], y + s * pts[:, 0] + c * pts[:, 1]))


def to_world(extraction: Extraction, pose: Sequence[float]) -> Extraction:
    """A copy of ``extraction`` with its lines and endpoints in the world frame.

    Parameters
    ----------
    extraction:
        Features in the sensor frame.
    pose:
        Sensor pose ``(x, y, theta)`` in the world frame (``Scan.pose``).

    Returns
    -------
    Extraction
        Same segments, indices, method and parameters; ``lines`` (rho, alpha,
        endpoints) and ``covariances`` transformed; ``rms`` unchanged.
    """
    x, y, theta = (float(v) for v in pose)
    lines = np.array(extraction.lines, dtype=np.float64, copy=True)
    for x_column, y_column in ((START_X, START_Y), (END_X, END_Y)):
        columns = [x_column, y_column]
        lines[:, columns] = points_to_world(lines[:, columns], pose)
    alpha = lines[:, ALPHA] + theta
    rho = lines[:, RHO] + x * np.cos(alpha) + y * np.sin(alpha)
    d_rho_d_alpha = -x * np.sin(alpha) + y * np.cos(alpha)
    flip = rho < 0.0
    sign = np.where(flip, -1.0, 1.0)
    lines[:, RHO] = sign * rho
    lines[:, ALPHA] = _wrap(alpha + np.where(flip, math.pi, 0.0))
    jacobian = np.zeros((len(lines), 2, 2))
    jacobian[:, 0, 0] = sign
    jacobian[:, 0, 1] = sign * d_rho_d_alpha
    jacobian[:, 1, 1] = 1.0
    covariances = jacobian @ extraction.covariances @ jacobian.transpose(0, 2, 1)
    return Extraction(
        first=extraction.first,
        last=extraction.last,
        n_points=extraction.n_points,
        lines=lines,
        covariances=covariances,
        breakpoints=extraction.breakpoints,
        corners=extraction.corners,
        outliers=extraction.outliers,
        end_kinds=extraction.end_kinds,
        method=extraction.method,
        params=extraction.params,
    )


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in ``(-pi, pi]``."""
    wrapped = np.mod(angle + math.pi, 2.0 * math.pi) - math.pi
    return np.where(wrapped <= -math.pi, wrapped + 2.0 * math.pi, wrapped)
