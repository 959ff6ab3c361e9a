"""Parameter specifications: defaults, validation and presets shared by all methods."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from scanlines.errors import ParameterError

__all__ = [
    "Param",
    "choice",
    "float_pair",
    "int_at_least",
    "number",
    "optional",
    "resolve",
    "with_default",
]

Check = Callable[[str, Any], Any]


@dataclass(frozen=True, slots=True)
class Param:
    """One parameter of a method: its default, a validator and a one-line doc."""

    default: Any
    check: Check
    doc: str


def with_default(param: Param, default: Any, note: str = "") -> Param:
    """``param`` with another default (and a note appended to its doc), same validation."""
    return Param(default, param.check, param.doc + (f" ({note})" if note else ""))


def segment_params(
    min_points: int, min_length: float = 0.0, range_sigma: float | str = "auto"
) -> dict[str, Param]:
    """The output parameters every method has, with that method's defaults."""
    return {
        "min_points": Param(min_points, int_at_least(2), "fewest points of a segment"),
        "min_length": Param(min_length, number(low=0.0), "shortest segment (m)"),
        "range_sigma": Param(
            range_sigma,
            auto_or(number(low=0.0, low_open=True)),
            "range noise of the covariances (m), or auto: the noise model's",
        ),
    }


def number(*, low: float = -math.inf, high: float = math.inf, low_open: bool = False) -> Check:
    """A real number in ``[low, high]`` (``(low, high]`` when ``low_open``)."""

    def check(name: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ParameterError(f"{name} must be a number, got {value!r}") from None
        out = float(value)
        below = out <= low if low_open else out < low
        if math.isnan(out) or below or out > high:
            bracket = "(" if low_open else "["
            raise ParameterError(f"{name} must be in {bracket}{low}, {high}], got {value!r}")
        return out

    return check


def int_at_least(low: int) -> Check:
    """An integer ``>= low``."""

    def check(name: str, value: Any) -> int:
        if isinstance(value, bool):
            raise ParameterError(f"{name} must be an integer, got {value!r}")
        try:
            out = int(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be an integer, got {value!r}") from None
        if out != value and not (isinstance(value, str) and str(out) == value.strip()):
            raise ParameterError(f"{name} must be an integer, got {value!r}")
        if out < low:
            raise ParameterError(f"{name} must be >= {low}, got {value!r}")
        return out

    return check


def choice(*options: Any) -> Check:
    """One of ``options`` (strings are compared case-sensitively)."""

    def check(name: str, value: Any) -> Any:
        for option in options:
            if value == option and type(value) is type(option):
                return option
        if isinstance(value, str):
            lowered = value.strip().lower()
            for option in options:
                if isinstance(option, bool) and lowered in ("true", "false", "1", "0"):
                    if (lowered in ("true", "1")) == option:
                        return option
                elif str(option) == lowered:
                    return option
        valid = ", ".join(repr(o) for o in options)
        raise ParameterError(f"{name} must be one of {valid}, got {value!r}")

    return check


def optional(inner: Check, *, none_words: tuple[str, ...] = ("none", "off")) -> Check:
    """``None`` (or one of ``none_words`` as a string) or a value accepted by ``inner``."""

    def check(name: str, value: Any) -> Any:
        if value is None or (isinstance(value, str) and value.strip().lower() in none_words):
            return None
        return inner(name, value)

    return check


def auto_or(inner: Check) -> Check:
    """The string ``"auto"`` or a value accepted by ``inner``."""

    def check(name: str, value: Any) -> Any:
        if isinstance(value, str) and value.strip().lower() == "auto":
            return "auto"
        return inner(name, value)

    return check


def float_pair(*, low: float = 0.0) -> Check:
    """Two numbers ``(a, b)`` with ``low <= a < b``; a string "a,b" is accepted."""
    element = number(low=low)

    def check(name: str, value: Any) -> tuple[float, float]:
        if isinstance(value, str):
            value = [part for part in value.replace("(", "").replace(")", "").split(",") if part]
        try:
            first, second = value
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be a pair (a, b), got {value!r}") from None
        a, b = element(name, first), element(name, second)
        if not a < b:
            raise ParameterError(f"{name} must have a < b, got {value!r}")
        return (a, b)

    return check


def resolve(
    method: str,
    spec: Mapping[str, Param],
    presets: Mapping[str, Mapping[str, Any]],
    preset: str | None,
    overrides: Mapping[str, Any],
) -> dict[str, Any]:
    """Defaults, then the preset, then ``overrides``; every value validated.

    Raises
    ------
    ParameterError
        For an unknown preset or parameter (listing the valid ones) or a bad value.
    """
    values = {name: p.default for name, p in spec.items()}
    if preset is not None:
        if preset not in presets:
            valid = ", ".join(sorted(presets)) or "none"
            raise ParameterError(f"unknown preset {preset!r} for method {method!r}; valid: {valid}")
        values.update(presets[preset])
    unknown = sorted(set(overrides) - set(spec))
    if unknown:
        valid = ", ".join(sorted(spec))
        raise ParameterError(
            f"unknown parameter(s) {', '.join(unknown)} for method {method!r}; valid: {valid}"
        )
    values.update(overrides)
    return {name: spec[name].check(name, value) for name, value in values.items()}
