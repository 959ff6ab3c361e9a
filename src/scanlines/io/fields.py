"""Field naming for fixed-layout text records, so errors can name the bad field."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["FieldLayout"]


class FieldLayout:
    """The order of the numeric fields of a record: scalars and arrays.

    Parameters
    ----------
    parts:
        ``(name, length)`` pairs in order. A part of length ``None`` is a scalar
        named ``name``; a part with a length is an array whose elements are
        named ``name[k]``.

    Examples
    --------
    >>> layout = FieldLayout([("num", None), ("range", 3), ("x", None)])
    >>> [layout.name(i) for i in range(5)]
    ['num', 'range[0]', 'range[1]', 'range[2]', 'x']
    """

    def __init__(self, parts: Sequence[tuple[str, int | None]]) -> None:
        self._parts = list(parts)

    def name(self, position: int) -> str:
        """Name of the field at ``position`` (0-based among the parsed fields)."""
        offset = 0
        for name, length in self._parts:
            size = 1 if length is None else length
            if position < offset + size:
                return name if length is None else f"{name}[{position - offset}]"
            offset += size
        return f"field[{position}]"

    def __len__(self) -> int:
        return sum(1 if length is None else length for _, length in self._parts)
