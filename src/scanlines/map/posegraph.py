"""A planar pose graph (SE(2) poses, relative-pose edges) solved by sparse Gauss-Newton.

Each edge ``(i, j, z, information)`` says that pose ``j`` seen from pose ``i`` is ``z``;
its error is ``e = z^-1 o (x_i^-1 o x_j)`` as ``(x, y, theta)``, weighted by the edge's
information matrix (the inverse of its covariance). :func:`optimise` minimises the sum of
``e' I e`` by Gauss-Newton steps on the whitened residuals, the Jacobian a
``scipy.sparse`` matrix (3 rows per edge, 3 columns per pose, the first pose held fixed)
and each step solved by a sparse LU factorisation (``scipy.sparse.linalg.splu``).
:func:`optimise_least_squares` solves the same problem with
``scipy.optimize.least_squares`` and the same sparse Jacobian, for comparison
(``docs/decisions/pose-graph.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

__all__ = ["Edge", "PoseGraph", "Solution", "edge_errors", "optimise", "optimise_least_squares"]


class Edge(NamedTuple):
    """Pose ``j`` seen from pose ``i`` (``measurement``: x, y, theta), its information
    matrix (3 x 3) and its ``kind`` (``"track"``, ``"loop"``)."""

    i: int
    j: int
    measurement: tuple[float, float, float]
    information: np.ndarray
    kind: str = "track"


@dataclass
class PoseGraph:
    """Poses (N x 3, x y theta) and the edges between them."""

    poses: np.ndarray
    edges: list[Edge] = field(default_factory=list)

    def add(self, edge: Edge) -> None:
        if not (0 <= edge.i < len(self.poses) and 0 <= edge.j < len(self.poses)):
            raise ValueError(f"edge {edge.i} -> {edge.j}: no such pose (of {len(self.poses)})")
        self.edges.append(edge)


class Solution(NamedTuple):
    """Optimised poses (N x 3), the Gauss-Newton steps taken, the cost (sum of squared
    whitened errors) before and after."""

    poses: np.ndarray
    iterations: int
    initial_cost: float
    cost: float


def _wrap(angle):
    return np.remainder(np.asarray(angle) + np.pi, 2.0 * np.pi) - np.pi


class _Arrays(NamedTuple):
    i: np.ndarray
    j: np.ndarray
    z: np.ndarray  # E x 3
    root: np.ndarray  # E x 3 x 3: L' with L L' = information (whitening)


def _arrays(edges: list[Edge]) -> _Arrays:
    info = np.array([e.information for e in edges], dtype=np.float64).reshape(-1, 3, 3)
    root = np.transpose(np.linalg.cholesky(info), (0, 2, 1))
    return _Arrays(
        np.array([e.i for e in edges], dtype=np.intp),
        np.array([e.j for e in edges], dtype=np.intp),
        np.array([e.measurement for e in edges], dtype=np.float64).reshape(-1, 3),
        root,
    )


def _errors_and_jacobians(poses: np.ndarray, a: _Arrays):
    """Each edge's error (E x 3) and its Jacobians by pose i and pose j (E x 3 x 3)."""
    xi, xj = poses[a.i], poses[a.j]
    ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
    cz, sz = np.cos(a.z[:, 2]), np.sin(a.z[:, 2])
    d = xj[:, :2] - xi[:, :2]
    # the pose j in i's frame, then the difference to z in z's frame
    local = np.column_stack((ci * d[:, 0] + si * d[:, 1], -si * d[:, 0] + ci * d[:, 1]))
    dz = local - a.z[:, :2]
    error = np.column_stack(
        (cz * dz[:, 0] + sz * dz[:, 1], -sz * dz[:, 0] + cz * dz[:, 1],
         _wrap(xj[:, 2] - xi[:, 2] - a.z[:, 2]))
    )  # fmt: skip
    n = len(a.i)
    rz_t = np.empty((n, 2, 2))
    rz_t[:, 0, 0], rz_t[:, 0, 1], rz_t[:, 1, 0], rz_t[:, 1, 1] = cz, sz, -sz, cz
    ri_t = np.empty((n, 2, 2))
    ri_t[:, 0, 0], ri_t[:, 0, 1], ri_t[:, 1, 0], ri_t[:, 1, 1] = ci, si, -si, ci
    rot = rz_t @ ri_t
    # d(Ri' d)/d(theta_i) = (local_y, -local_x)
    turn = np.einsum("eab,eb->ea", rz_t, np.column_stack((local[:, 1], -local[:, 0])))
    jac_i = np.zeros((n, 3, 3))
    jac_j = np.zeros((n, 3, 3))
    jac_i[:, :2, :2], jac_i[:, :2, 2], jac_i[:, 2, 2] = -rot, turn, -1.0
    jac_j[:, :2, :2], jac_j[:, 2, 2] = rot, 1.0
    return error, jac_i, jac_j


def edge_errors(graph: PoseGraph, poses: np.ndarray | None = None) -> np.ndarray:
    """Each edge's squared Mahalanobis error ``e' I e`` at ``poses`` (default: the graph's)."""
    if not graph.edges:
        return np.zeros(0)
    a = _arrays(graph.edges)
    error, _, _ = _errors_and_jacobians(graph.poses if poses is None else poses, a)
    white = np.einsum("eab,eb->ea", a.root, error)
    return np.sum(white**2, axis=1)


def _system(poses: np.ndarray, a: _Arrays):
    """The whitened residuals (3E) and their sparse Jacobian (3E x 3(N-1)), pose 0 fixed."""
    from scipy import sparse

    error, jac_i, jac_j = _errors_and_jacobians(poses, a)
    residual = np.einsum("eab,eb->ea", a.root, error).reshape(-1)
    wi = (a.root @ jac_i).reshape(-1)
    wj = (a.root @ jac_j).reshape(-1)
    n = len(a.i)
    rows = np.repeat(np.arange(3 * n).reshape(n, 3), 3, axis=1).reshape(-1)
    offsets = np.tile(np.arange(3), 3 * n)
    cols_i = (np.repeat(a.i, 9) * 3 + offsets) - 3
    cols_j = (np.repeat(a.j, 9) * 3 + offsets) - 3
    rows, cols = np.concatenate((rows, rows)), np.concatenate((cols_i, cols_j))
    values = np.concatenate((wi, wj))
    keep = cols >= 0  # pose 0 is the fixed anchor
    shape = (3 * n, 3 * (len(poses) - 1))
    return residual, sparse.csr_matrix((values[keep], (rows[keep], cols[keep])), shape=shape)


def optimise(graph: PoseGraph, iterations: int = 20, tolerance: float = 1e-6) -> Solution:
    """Gauss-Newton on ``graph`` from its poses (the first pose fixed); stops when a step
    moves no pose by more than ``tolerance`` (metres, radians)."""
    from scipy.sparse import identity
    from scipy.sparse.linalg import splu

    poses = np.array(graph.poses, dtype=np.float64)
    if not graph.edges or len(poses) < 2:
        return Solution(poses, 0, 0.0, 0.0)
    a = _arrays(graph.edges)
    residual, jac = _system(poses, a)
    initial = cost = float(residual @ residual)
    done = 0
    while done < iterations:
        done += 1
        normal = (jac.T @ jac).tocsc()
        normal = normal + identity(normal.shape[0], format="csc") * 1e-9
        step = -splu(normal).solve(jac.T @ residual)
        poses[1:] += step.reshape(-1, 3)
        poses[:, 2] = _wrap(poses[:, 2])
        residual, jac = _system(poses, a)
        cost = float(residual @ residual)
        if np.abs(step).max() < tolerance:
            break
    return Solution(poses, done, initial, cost)


def optimise_least_squares(graph: PoseGraph, tolerance: float = 1e-8) -> Solution:
    """The same problem by ``scipy.optimize.least_squares`` (trust region, the sparse
    Jacobian of :func:`optimise`, LSMR steps)."""
    from scipy.optimize import least_squares

    poses = np.array(graph.poses, dtype=np.float64)
    a = _arrays(graph.edges)
    first = poses[:1]

    def full(v: np.ndarray) -> np.ndarray:
        return np.vstack((first, v.reshape(-1, 3)))

    residual, _ = _system(poses, a)
    found = least_squares(
        lambda v: _system(full(v), a)[0], poses[1:].reshape(-1),
        jac=lambda v: _system(full(v), a)[1], method="trf", x_scale="jac",
        xtol=tolerance, ftol=tolerance, gtol=tolerance,
    )  # fmt: skip
    out = full(found.x)
    out[:, 2] = _wrap(out[:, 2])
    return Solution(out, int(found.nfev), float(residual @ residual), float(2.0 * found.cost))
