"""Old import path, kept only for ``tests/test_steps.py``: use :mod:`scanlines.evaluation.scenes`.

Remove this module once that test imports ``make_scene`` from its new home.
"""

from scanlines.evaluation.scenes import make_scene

__all__ = ["make_scene"]
