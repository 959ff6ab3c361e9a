"""The arrays the compiled steps take: contiguous, of the type the kernel reads."""

from __future__ import annotations

import numpy as np

__all__ = ["bools", "float64s", "int64s"]


def int64s(values) -> np.ndarray:
    """``values`` as a C-contiguous int64 array (no copy when they are one already)."""
    return np.ascontiguousarray(values, dtype=np.int64)


def float64s(values) -> np.ndarray:
    """``values`` as a C-contiguous float64 array (no copy when they are one already)."""
    return np.ascontiguousarray(values, dtype=np.float64)


def bools(values) -> np.ndarray:
    """``values`` as a C-contiguous bool array (no copy when they are one already)."""
    return np.ascontiguousarray(values, dtype=np.bool_)
