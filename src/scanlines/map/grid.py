"""The spatial index of association: which boxes of two sets overlap.

A uniform grid over the boxes, each box listed under the cells it covers (sorted integer
keys, binary search); the pairs sharing a cell are then cut to those whose boxes meet, each
pair once. The cells are :data:`CELL` metres, anchored at whole multiples of the cell, unless
the boxes would then cover more than :data:`CELLS_PER_BOX` cells each on average (a map
spread over a huge area, a line kilometres long): the cell doubles until they do not, so
the index's memory and work are bounded by the number of boxes, not by their extent. The
pairs found do not depend on the cell; only the work does.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BLOCK", "CELL", "CELLS_PER_BOX", "box_pairs", "boxes_of"]

#: The side of a cell of the spatial index (metres), where the boxes allow it.
CELL = 2.0
#: Cells listed per box, on average, before the cells grow.
CELLS_PER_BOX = 64
#: Candidate pairs of the spatial index looked at together.
BLOCK = 1 << 16
#: Bits of a cell's index along one axis in a key.
_BITS = 31


def boxes_of(ends: np.ndarray, margin: float) -> np.ndarray:
    """``N x 4`` bounding boxes ``(x_min, y_min, x_max, y_max)`` of ``N x 2 x 2`` endpoints,
    grown by ``margin`` on every side."""
    return np.hstack((ends.min(axis=1) - margin, ends.max(axis=1) + margin))


class _Grid:
    """Cells of side ``cell`` (metres), counted from the cell ``anchor`` (two integers), over
    the ``N x 4`` ``boxes``: :meth:`cells` lists the cells of rows of them."""

    def __init__(self, boxes: np.ndarray) -> None:
        low = boxes[:, :2].min(axis=0)
        span = float((boxes[:, 2:].max(axis=0) - low).max())
        cell = max(CELL, span / 2 ** (_BITS - 1))  # every cell index fits its bits
        cap = CELLS_PER_BOX * len(boxes) + 4096
        while True:
            anchor = np.floor(low / cell)
            lo = np.floor(boxes[:, :2] / cell) - anchor
            hi = np.floor(boxes[:, 2:] / cell) - anchor
            size = hi - lo + 1.0
            if float(np.dot(size[:, 0], size[:, 1])) <= cap:
                break
            cell *= 2.0
        self.cell, self.anchor = cell, anchor
        self._lo, self._size = lo.astype(np.int64), size.astype(np.int64)

    def cells(self, rows: slice) -> tuple[np.ndarray, np.ndarray]:
        """``(keys, rows)``: the cells each box of ``rows`` (of the boxes the grid was made
        of) covers, one pair per cell, keys as integers, rows counted from the slice's
        start."""
        lo, size = self._lo[rows], self._size[rows]
        count = size[:, 0] * size[:, 1]
        owner = np.repeat(np.arange(len(lo)), count)
        local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        cx = lo[owner, 0] + local % size[owner, 0]
        cy = lo[owner, 1] + local // size[owner, 0]
        return (cx << _BITS) | cy, owner

    def keys_at(self, points: np.ndarray) -> np.ndarray:
        """The key of the cell of each ``K x 2`` point."""
        cell = (np.floor(points / self.cell) - self.anchor).astype(np.int64)
        return (cell[:, 0] << _BITS) | cell[:, 1]


def box_pairs(queries: np.ndarray, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(q, b)`` of the ``queries`` and ``boxes`` (``N x 4``, finite) that
    overlap. Cost: the boxes near each query, not all of them."""
    empty = np.zeros(0, dtype=np.int64)
    if not len(queries) or not len(boxes):
        return empty, empty
    grid = _Grid(np.vstack((queries, boxes)))
    box_keys, box_rows = grid.cells(slice(len(queries), None))
    order = np.argsort(box_keys, kind="stable")
    box_keys, box_rows = box_keys[order], box_rows[order]
    query_keys, query_rows = grid.cells(slice(0, len(queries)))
    starts = np.searchsorted(box_keys, query_keys, side="left")
    stops = np.searchsorted(box_keys, query_keys, side="right")
    count = stops - starts
    # The candidate pairs are looked at in blocks of about BLOCK: the peak memory of a merge
    # stays bounded however many lines the map holds.
    total = np.cumsum(count)
    edges = np.searchsorted(total, np.arange(BLOCK, int(total[-1]) if len(total) else 0, BLOCK))
    found_q, found_b = [], []
    for lo, hi in zip(
        np.concatenate(([0], edges)), np.concatenate((edges, [len(count)])), strict=True
    ):
        if hi <= lo:
            continue
        q, b = _cell_pairs(
            grid, boxes, queries, box_rows, query_keys[lo:hi], query_rows[lo:hi], starts[lo:hi],
            count[lo:hi],
        )  # fmt: skip
        found_q.append(q)
        found_b.append(b)
    if not found_q:
        return empty, empty
    return np.concatenate(found_q), np.concatenate(found_b)


def _cell_pairs(grid, boxes, queries, box_rows, query_keys, query_rows, starts, count):
    """The overlapping pairs among the candidates of some query cells, each pair once."""
    q = np.repeat(query_rows, count)
    key = np.repeat(query_keys, count)
    local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    b = box_rows[np.repeat(starts, count) + local]
    box, query = boxes[b], queries[q]
    hit = (
        (box[:, 0] <= query[:, 2])
        & (box[:, 2] >= query[:, 0])
        & (box[:, 1] <= query[:, 3])
        & (box[:, 3] >= query[:, 1])
    )
    # A pair meets in several cells: keep it once, in the cell of its overlap's low corner.
    corner = np.maximum(box[:, :2], query[:, :2])
    hit &= grid.keys_at(corner) == key
    return q[hit].astype(np.int64), b[hit].astype(np.int64)
