"""The kinds of token the compiled number reader tells apart."""

NOT_A_NUMBER, INTEGER, DECIMAL = 0, 1, 2
"""Kinds of token: not one :func:`scanlines.io.numbers.number_fields` reads, digits only
(with a sign), any other number it reads."""
