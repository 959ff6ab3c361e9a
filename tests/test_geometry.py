"""The one point-to-line step the scan-to-scan ICP and the scan-to-map alignment share."""

from __future__ import annotations

import numpy as np
import pytest

from scanlines.geometry.registration import point_to_line_step


def _room(shift: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points on two perpendicular walls (x = 2, y = 1), moved by ``shift``: their normals
    and residuals."""
    along = np.linspace(-1.0, 1.0, 21)
    points = np.vstack(
        (np.column_stack((np.full(21, 2.0), along)), np.column_stack((along, np.full(21, 1.0))))
    ) + np.array(shift)
    normals = np.vstack((np.tile([1.0, 0.0], (21, 1)), np.tile([0.0, 1.0], (21, 1))))
    residuals = np.sum(normals * points, axis=1) - np.repeat([2.0, 1.0], 21)
    return points, normals, residuals


def test_a_step_brings_shifted_points_back_onto_their_lines():
    points, normals, residuals = _room((0.01, -0.005))
    step = point_to_line_step(points, normals, residuals, huber=0.02)
    assert step is not None
    assert step.update == pytest.approx([-0.01, 0.005, 0.0], abs=1e-9)
    ridged = point_to_line_step(points, normals, residuals, huber=0.02, ridge=1e-6)
    assert ridged.update == pytest.approx(step.update, abs=1e-6)
    assert np.array_equal(ridged.normal, step.normal)


def test_one_wall_gives_no_step_without_a_ridge_and_a_still_axis_with_one():
    points, normals, residuals = _room((0.01, 0.0))
    points, normals, residuals = points[:21], normals[:21], residuals[:21]  # the wall x = 2
    no_rotation = np.zeros_like(points)  # turning about every point: no lever
    assert point_to_line_step(no_rotation, normals, residuals, huber=0.02) is None
    ridged = point_to_line_step(no_rotation, normals, residuals, huber=0.02, ridge=1e-6)
    assert ridged.update[0] == pytest.approx(-0.01, abs=1e-6)
    assert ridged.update[1] == pytest.approx(0.0, abs=1e-12)  # along the wall: held
