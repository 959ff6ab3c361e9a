"""scanlines: line segments, breakpoints and corners from 2D LiDAR scans.

The public API is small::

    from scanlines import Scan, extract
    scan = Scan(ranges, angle_min=-1.57, angle_increment=0.0175)
    result = extract(scan)                      # the paper's adaptive method, better defaults
    result = extract(scan, preset="paper")      # the paper, literally
    for seg in result.segments: ...

``import scanlines`` is quick: the names below are imported on first use (PEP 562),
so the command line can set itself up (Ctrl-C handling) before anything else loads. The
CLI, plots and log readers import their own dependencies when used.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from scanlines.errors import LogFormatError, ParameterError, ScanError, ScanlinesError

if TYPE_CHECKING:
    from scanlines import methods  # noqa: F401
    from scanlines.extraction import Extraction, Segment
    from scanlines.extractor import Extractor, extract, method_info, method_names
    from scanlines.scan import Scan

__version__ = "0.1.0"

_LAZY = {
    "Extraction": "scanlines.extraction",
    "Segment": "scanlines.extraction",
    "Extractor": "scanlines.extractor",
    "extract": "scanlines.extractor",
    "method_info": "scanlines.extractor",
    "method_names": "scanlines.extractor",
    "Scan": "scanlines.scan",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
    elif name == "methods":  # the package of the methods
        value = importlib.import_module("scanlines.methods")
    else:
        raise AttributeError(f"module 'scanlines' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY, "methods"})


__all__ = [
    "Extraction",
    "Extractor",
    "LogFormatError",
    "ParameterError",
    "Scan",
    "ScanError",
    "ScanlinesError",
    "Segment",
    "__version__",
    "extract",
    "method_info",
    "method_names",
]
