"""scanlines: line segments, breakpoints and corners from 2D LiDAR scans.

The public API is small::

    from scanlines import Scan, extract
    scan = Scan(ranges, angle_min=-1.57, angle_increment=0.0175)
    result = extract(scan)                      # the paper's adaptive method, better defaults
    result = extract(scan, preset="paper")      # the paper, literally
    for seg in result.segments: ...

``import scanlines`` needs only numpy; the CLI, plots and log readers import
their own dependencies when used.
"""

from __future__ import annotations

from scanlines import methods  # noqa: F401 (the package; calling it: deprecated alias)
from scanlines.errors import LogFormatError, ParameterError, ScanError, ScanlinesError
from scanlines.extraction import Extraction, Segment
from scanlines.extractor import Extractor, extract, method_info, method_names
from scanlines.scan import Scan

__version__ = "0.1.0"

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
