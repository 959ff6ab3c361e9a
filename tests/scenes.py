"""Hand-built scans with known geometry for the tests (exact ray casting on wall segments)."""

from __future__ import annotations

import math

import numpy as np

from scanlines import Scan


def cast(
    walls: list[tuple[tuple[float, float], tuple[float, float]]], angles: np.ndarray
) -> np.ndarray:
    """Range along each bearing to the nearest wall segment (inf where none is hit)."""
    walls_arr = np.asarray(walls, dtype=float)  # (W, 2, 2)
    p, q = walls_arr[:, 0], walls_arr[:, 1]
    e = q - p
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
    denom = dx * e[None, :, 1] - dy * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[None, :, 0] * e[None, :, 1] - p[None, :, 1] * e[None, :, 0]) / denom
        u = (p[None, :, 0] * dy - p[None, :, 1] * dx) / denom
    hit = (np.abs(denom) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
    return np.where(hit, t, np.inf).min(axis=1)


def square_room(half: float = 2.0) -> list:
    c = [(-half, -half), (half, -half), (half, half), (-half, half)]
    return [(c[i], c[(i + 1) % 4]) for i in range(4)]


def scan_of(
    walls,
    *,
    fov_deg: float,
    step_deg: float,
    sigma: float = 0.0,
    seed: int = 0,
    start_deg: float | None = None,
    full_circle: bool = False,
) -> Scan:
    step = math.radians(step_deg)
    n = round(fov_deg / step_deg) + (0 if full_circle else 1)
    angle_min = math.radians(-fov_deg / 2 if start_deg is None else start_deg)
    angles = angle_min + step * np.arange(n)
    ranges = cast(walls, angles)
    if sigma:
        ranges = ranges + np.random.default_rng(seed).normal(0.0, sigma, n)
    return Scan(ranges, angle_min, step)


def beam_of(scan: Scan, bearing: float) -> int:
    """Index of the beam nearest ``bearing`` (radians)."""
    return int(np.argmin(np.abs(np.angle(np.exp(1j * (scan.angles - bearing))))))


def returns_of(scan: Scan):
    """The :class:`~scanlines.steps.returns.Returns` of ``scan`` (local frame), as the
    methods build them."""
    from scanlines.steps.returns import valid_returns

    local = scan.angle_increment * np.arange(len(scan))
    return valid_returns(scan.ranges, scan.valid, np.cos(local), np.sin(local))
