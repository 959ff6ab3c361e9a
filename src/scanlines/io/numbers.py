"""The numbers of a text record in one compiled pass: the fast path of the text readers.

``str.split`` and ``np.array(tokens, dtype=float)`` cost about 90 us for a 180-beam
CARMEN record, more than extracting its features. :func:`number_fields` splits and
parses a whole line in one kernel call instead, for the tokens whose value it can give
exactly: an optional sign, decimal digits with at most one point, an optional exponent,
whose significand is at most 2^53 and whose decimal exponent lies in [-22, 22]. Both the
significand and the power of ten are then exact doubles, so one IEEE multiplication or
division rounds the value correctly: it is the double ``float(token)`` gives (Clinger's
fast path, "How to read floating point numbers accurately", PLDI 1990). Any other token
(``nan``, ``inf``, ``1_000``, 17 significant digits, text) is reported as not a number,
and the reader parses that record the slow way, which also names a bad field.

The kernel is C++ (``cpp/scanlines/io/numbers.cpp``).
"""

from __future__ import annotations

import numpy as np

from scanlines._core import read_fields
from scanlines.io.number_kinds import DECIMAL, INTEGER, NOT_A_NUMBER

__all__ = ["DECIMAL", "INTEGER", "NOT_A_NUMBER", "NumberFields", "number_fields"]


class NumberFields:
    """The tokens of one line: ``values[k]`` (NaN where ``kinds[k]`` is
    :data:`NOT_A_NUMBER`), ``kinds[k]``, and ``texts``, the positions of the tokens not
    read as numbers (a list: a record's layout is checked against it in Python without
    a numpy call); ``len(self)`` tokens in all."""

    __slots__ = ("kinds", "texts", "values")

    def __init__(self, values: np.ndarray, kinds: np.ndarray, texts: list[int]) -> None:
        self.values = values
        self.kinds = kinds
        self.texts = texts

    def __len__(self) -> int:
        return int(self.values.shape[0])


def number_fields(line: str) -> NumberFields | None:
    """The whitespace-separated tokens of ``line`` (split as ``str.split()`` splits),
    each read as a number where the module docstring's fast path allows; ``None`` for a
    line that is not ASCII (the caller splits it the slow way)."""
    try:
        data = line.encode("ascii")
    except UnicodeEncodeError:
        return None
    values, kinds, texts = read_fields(data)
    return NumberFields(values, kinds, texts)
