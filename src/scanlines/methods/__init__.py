"""Extractors, one module each; the registry maps method names to modules.

Every method module defines ``NAME``, ``PARAMS`` (name -> :class:`~scanlines.params.Param`),
``PRESETS`` (preset name -> overrides) and ``run(seq, angle_min, params) -> Extraction``.
"""

from __future__ import annotations

from types import ModuleType

from scanlines.methods import (
    adaptive,
    hough,
    iepf,
    line_regression,
    line_tracking,
    pdbs,
    ransac,
    split_merge,
)

REGISTRY: dict[str, ModuleType] = {
    module.NAME: module
    for module in (
        adaptive,
        iepf,
        pdbs,
        split_merge,
        line_tracking,
        line_regression,
        ransac,
        hough,
    )
}

__all__ = ["REGISTRY"]
