"""The kernels of :mod:`scanlines.io.numbers` (a module of their own: it is imported only
once numba is loaded, so that importing the readers does not load numba)."""

from __future__ import annotations

import numpy as np

from scanlines._jit import kernel
from scanlines.io.number_kinds import DECIMAL, INTEGER, NOT_A_NUMBER

__all__ = ["POWERS_OF_TEN", "read_fields"]

POWERS_OF_TEN = np.array([float(10**k) for k in range(23)])  # exact: 5^22 < 2^53
_LARGEST_EXACT = 2**53


@kernel
def is_space(byte):
    # str.split() separators among ASCII: \t \n \v \f \r, \x1c-\x1f and the space
    return byte == 32 or 9 <= byte <= 13 or 28 <= byte <= 31


@kernel
def read_fields(data, powers):
    n = data.shape[0]
    values = np.empty(n // 2 + 1)
    kinds = np.zeros(n // 2 + 1, dtype=np.int8)
    texts = np.empty(n // 2 + 1, dtype=np.int64)
    count = 0
    text_count = 0
    i = 0
    while i < n:
        if is_space(data[i]):
            i += 1
            continue
        end = i
        while end < n and not is_space(data[end]):
            end += 1
        values[count], kinds[count] = read_number(data, np.int64(i), end, powers)
        if kinds[count] == NOT_A_NUMBER:
            texts[text_count] = count
            text_count += 1
        count += 1
        i = end
    return values[:count], kinds[:count], texts[:text_count]


@kernel
def read_number(data, start, end, powers):
    """``(value, kind)`` of the token ``data[start:end]`` (the rule of
    :mod:`scanlines.io.numbers`)."""
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
        byte = np.int64(data[i])  # not uint8 arithmetic (plain Python would wrap around)
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
            exponent = exponent * 10 + (np.int64(data[i]) - 48)
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
