"""Old import path, kept only for ``tests/methods/test_method_common.py``: use
:mod:`scanlines.evaluation.metrics` and :mod:`scanlines.evaluation.scores`.

Remove this module once that test imports these names from their new homes.
"""

from scanlines.evaluation.metrics import aggregate, score
from scanlines.evaluation.scores import Summary

__all__ = ["Summary", "aggregate", "score"]
