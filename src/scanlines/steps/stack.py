"""A stack of scans through a method in one kernel call: each scan's result arrays
(:func:`~scanlines.steps.assemble.assemble`'s output) appended to one flat table.

A method's stack kernel is a loop over the rows that calls its per-scan kernel and
:func:`add_row`; the table it returns is :func:`new_table`'s tuple ``(first, last,
n_points, lines, covariances, breakpoints, corners, outliers, end_kinds, counts,
used)``: the nine columns of :class:`~scanlines.extraction.ExtractionTable`, flat
(``lines`` holds 7 values per segment, ``covariances`` 4, ``end_kinds`` 2) and longer
than needed, ``counts`` (rows x 4) each scan's numbers of segments, breakpoints,
corners and outliers, and ``used`` those numbers summed.

Each method writes its own five-line loop: numba caches no kernel that takes another
kernel as an argument or closes over one (such a generic loop compiled again in every
process), and a cold cache is what a user waits for.
"""

from __future__ import annotations

import numpy as np

from scanlines._jit import kernel
from scanlines.extraction import N_LINE_COLUMNS

__all__ = ["add_row", "new_table"]

FIRST_CAPACITY = 16
"""Segments (and events of each kind) the table holds per scan before it grows."""


@kernel
def new_table(rows):
    """An empty table for ``rows`` scans."""
    size = rows * FIRST_CAPACITY
    index = np.empty(size, dtype=np.int64)
    return (
        index,
        index.copy(),
        index.copy(),
        np.empty(size * N_LINE_COLUMNS),
        np.empty(size * 4),
        index.copy(),
        index.copy(),
        index.copy(),
        np.empty(size * 2, dtype=np.int8),
        np.zeros((rows, 4), dtype=np.int64),
        np.zeros(4, dtype=np.int64),
    )


@kernel
def add_row(table, row, result):
    """``table`` with scan ``row``'s result arrays appended (grown where they do not fit)."""
    first, last, n_points, lines, covariances, breakpoints, corners, outliers, ends = table[:9]
    counts, used = table[9], table[10]
    at, n = used[0], result[0].shape[0]
    first, last = room_for(first, at, n), room_for(last, at, n)
    n_points = room_for(n_points, at, n)
    lines = room_for(lines, at * N_LINE_COLUMNS, n * N_LINE_COLUMNS)
    covariances, ends = room_for(covariances, at * 4, n * 4), room_for(ends, at * 2, n * 2)
    for j in range(n):
        k = at + j
        first[k], last[k], n_points[k] = result[0][j], result[1][j], result[2][j]
        for c in range(N_LINE_COLUMNS):
            lines[k * N_LINE_COLUMNS + c] = result[3][j, c]
        for c in range(4):
            covariances[k * 4 + c] = result[4][j, c // 2, c % 2]
        ends[k * 2], ends[k * 2 + 1] = result[8][j, 0], result[8][j, 1]
    breakpoints = appended(breakpoints, used[1], result[5])
    corners = appended(corners, used[2], result[6])
    outliers = appended(outliers, used[3], result[7])
    counts[row, 0], counts[row, 1] = n, result[5].shape[0]
    counts[row, 2], counts[row, 3] = result[6].shape[0], result[7].shape[0]
    used += counts[row]
    return (first, last, n_points, lines, covariances, breakpoints, corners, outliers, ends,
            counts, used)  # fmt: skip


@kernel
def appended(values, used, more):
    """``values`` (``used`` of them taken) with ``more`` written after them."""
    values = room_for(values, used, more.shape[0])
    for j in range(more.shape[0]):
        values[used + j] = more[j]
    return values


@kernel
def room_for(values, used, more):
    """``values``, or a copy at least twice as long when ``used + more`` do not fit."""
    if used + more <= values.shape[0]:
        return values
    grown = np.empty(max(2 * values.shape[0], used + more), dtype=values.dtype)
    for j in range(used):
        grown[j] = values[j]
    return grown
