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
"""

from __future__ import annotations

import numpy as np

from scanlines._jit import kernel

__all__ = ["DECIMAL", "INTEGER", "NOT_A_NUMBER", "NumberFields", "number_fields"]

NOT_A_NUMBER, INTEGER, DECIMAL = 0, 1, 2
"""Kinds of token: not one :func:`number_fields` reads, digits only (with a sign), any
other number it reads."""

_POWERS_OF_TEN = np.array([float(10**k) for k in range(23)])  # exact: 5^22 < 2^53
_LARGEST_EXACT = 2**53


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
    values, kinds, texts = _read_fields(np.frombuffer(data, dtype=np.uint8), _POWERS_OF_TEN)
    return NumberFields(values, kinds, texts.tolist())


@kernel
def _is_space(byte):
    # str.split() separators among ASCII: \t \n \v \f \r, \x1c-\x1f and the space
    return byte == 32 or 9 <= byte <= 13 or 28 <= byte <= 31


@kernel
def _read_fields(data, powers):
    n = data.shape[0]
    values = np.empty(n // 2 + 1)
    kinds = np.zeros(n // 2 + 1, dtype=np.int8)
    texts = np.empty(n // 2 + 1, dtype=np.int64)
    count = 0
    text_count = 0
    i = 0
    while i < n:
        if _is_space(data[i]):
            i += 1
            continue
        end = i
        while end < n and not _is_space(data[end]):
            end += 1
        values[count], kinds[count] = _read_number(data, i, end, powers)
        if kinds[count] == NOT_A_NUMBER:
            texts[text_count] = count
            text_count += 1
        count += 1
        i = end
    return values[:count], kinds[:count], texts[:text_count]


@kernel
def _read_number(data, start, end, powers):
    """``(value, kind)`` of the token ``data[start:end]`` (module docstring)."""
    failed = (np.nan, np.int8(NOT_A_NUMBER))
    i = start
    negative = data[i] == 45  # '-'
    if data[i] == 45 or data[i] == 43:  # '-' or '+'
        i += 1
    significand = 0
    digits = 0
    after_point = 0
    point = False
    exact = True
    while i < end:
        byte = data[i]
        if 48 <= byte <= 57:
            digits += 1
            if significand > _LARGEST_EXACT:
                exact = False
            else:
                significand = significand * 10 + (byte - 48)
            if point:
                after_point += 1
        elif byte == 46 and not point:  # '.'
            point = True
        else:
            break
        i += 1
    if digits == 0:
        return failed
    exponent = 0
    has_exponent = False
    if i < end and (data[i] == 101 or data[i] == 69):  # 'e' or 'E'
        has_exponent = True
        i += 1
        exponent_negative = i < end and data[i] == 45
        if i < end and (data[i] == 45 or data[i] == 43):
            i += 1
        exponent_digits = 0
        while i < end and 48 <= data[i] <= 57 and exponent_digits < 6:
            exponent = exponent * 10 + (data[i] - 48)
            exponent_digits += 1
            i += 1
        if exponent_digits == 0:
            return failed
        if exponent_negative:
            exponent = -exponent
    if i != end or not exact or significand > _LARGEST_EXACT:
        return failed
    power = exponent - after_point
    if power > 22 or power < -22:
        return failed
    value = float(significand)
    if power > 0:
        value = value * powers[power]
    elif power < 0:
        value = value / powers[-power]
    if negative:
        value = -value
    kind = INTEGER if not point and not has_exponent else DECIMAL
    return value, np.int8(kind)
