"""Scoring extractors against ground truth.

Import the modules by name; importing this package imports none of them, so that
:mod:`scanlines.sim` can use :mod:`~scanlines.evaluation.truth`::

    truth   the truth types (Truth, TrueSegments, BeamStatus); no simulator
"""

__all__ = ["truth"]
