"""Old import path, kept only for ``tests/test_api.py``: use :mod:`scanlines.viz.scans`.

Remove this module once that test imports ``plot_extraction`` from its new home.
"""

from scanlines.viz.scans import plot_extraction

__all__ = ["plot_extraction"]
