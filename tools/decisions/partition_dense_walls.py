"""The partition objective on a straight wall sampled more densely than its noise.

    python -m tools.decisions.partition_dense_walls

One straight wall of 16,384 returns with 1 cm noise across it, the returns ``spacing``
apart along it; the objective (chi2 / 2 of each segment's weighted total-least-squares fit
plus the penalty of 50 nats, weights ``1 / (sigma^2 + model_error^2)``, ``model_error`` 2
mm) of the whole wall as one segment against cuts into equal pieces. Where the pieces'
objective is lower, the exact optimum itself cuts the wall, whatever bound the search has.
"""

from __future__ import annotations

import numpy as np

N, SIGMA, MODEL_ERROR, PENALTY = 16384, 0.01, 0.002, 50.0
PIECES = (N, 1024, 256, 64)


def objective(x: np.ndarray, y: np.ndarray, length: int) -> float:
    weight = 1.0 / (SIGMA**2 + MODEL_ERROR**2)
    total = 0.0
    for start in range(0, N, length):
        points = np.stack((x[start : start + length], y[start : start + length]), axis=1)
        centred = points - points.mean(axis=0)
        total += 0.5 * weight * np.linalg.eigvalsh(centred.T @ centred)[0] + PENALTY
    return total


def main() -> None:
    noise = np.random.default_rng(0).normal(0.0, SIGMA, N)
    print("| spacing (m) | " + " | ".join(f"pieces of {p}" for p in PIECES) + " |")
    print("|---|" + "---|" * len(PIECES))
    for spacing in (3.1e-4, 1e-4, 3e-5):
        x = np.arange(N) * spacing
        row = " | ".join(f"{objective(x, noise, p):,.0f}" for p in PIECES)
        print(f"| {spacing:g} | {row} |")


if __name__ == "__main__":
    main()
