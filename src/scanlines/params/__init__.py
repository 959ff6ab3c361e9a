"""Parameter specifications: defaults, validation and presets of the methods and settings tables."""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from scanlines.errors import ParameterError
from scanlines.untrusted import clip, quote

__all__ = [
    "GROUPS",
    "MAX_COUNT",
    "MAX_METRES",
    "MAX_NUMBER",
    "MAX_SCANS",
    "Check",
    "KernelField",
    "Param",
    "Settings",
    "as_float",
    "auto_or",
    "choice",
    "coded",
    "flag",
    "float_pair",
    "integer",
    "kernel_settings",
    "number",
    "optional",
    "param_applies",
    "param_lines",
    "radians",
    "resolve",
    "with_default",
]


class Check:
    """A parameter's domain: ``check(name, value)`` returns the value converted (a string
    from the command line becomes a number...) or raises :class:`ParameterError`;
    :meth:`domain` describes the domain for :func:`~scanlines.method_info`."""

    def __call__(self, name: str, value: Any) -> Any:
        raise NotImplementedError

    def domain(self) -> dict[str, Any]:
        raise NotImplementedError

    def describe(self) -> str:
        """The domain in words, e.g. ``"float in (0, 90]"``."""
        raise NotImplementedError


@dataclass(frozen=True, slots=True)
class KernelField:
    """One field of a kernel's settings record: its name (``""``: the parameter's) and
    ``encode``, the parameter's resolved value -> the field's plain Python number (bool, int
    or float: the compiled kernels read nothing else)."""

    name: str
    encode: Callable[[Any], bool | int | float]


@dataclass(frozen=True, slots=True)
class Param:
    """One parameter of a method: its default, its domain (a :class:`Check`), a one-line
    doc and how a compiled kernel reads it: ``kernel`` fields of its settings record
    (``None``: the one field its check implies, see :func:`kernel_settings`; ``()``:
    none); ``applies``: when another parameter's value decides whether it is read."""

    default: Any
    check: Check
    doc: str
    kernel: tuple[KernelField, ...] | None = None
    #: ``(other, values, when_in)``: read only while the parameter ``other`` holds one of
    #: ``values`` (``when_in``) or none of them (not ``when_in``); ``None``: always read.
    #: The viewer hides a parameter that is not read; a method without ``other`` reads it.
    applies: tuple[str, tuple[Any, ...], bool] | None = None


def param_applies(param: Param, values: Mapping[str, Any]) -> bool:
    """Whether ``param`` is read with a method's parameter ``values`` (its ``applies``)."""
    if param.applies is None or param.applies[0] not in values:
        return True
    other, chosen, when_in = param.applies
    return (values[other] in chosen) == when_in


GROUPS = ("noise", "clustering", "segments", "events", "output")
"""What a method's settings are for, in the order a scan meets them: the range noise the
thresholds use; which neighbouring returns belong together (the clustering rule, the
denoising); how a cluster becomes segments (the method's own search); the corners and
breakpoints between segments; which segments are reported, with what covariances."""


@dataclass(frozen=True)
class Settings:
    """A method's parameters grouped by purpose (:data:`GROUPS`), each group a mapping
    name -> :class:`Param`; a name belongs to one group only.

    The user sees one flat namespace (:attr:`parameters`: ``Extractor("iepf",
    split_distance=0.05)``); a compiled kernel reads one settings record per group
    (:meth:`record`), which its binding turns into the kernel's typed settings.
    """

    noise: Mapping[str, Param] = field(default_factory=dict)
    clustering: Mapping[str, Param] = field(default_factory=dict)
    segments: Mapping[str, Param] = field(default_factory=dict)
    events: Mapping[str, Param] = field(default_factory=dict)
    output: Mapping[str, Param] = field(default_factory=dict)

    def __post_init__(self) -> None:
        seen: dict[str, str] = {}
        for group, params in self.groups().items():
            for name in params:
                if name in seen:
                    raise TypeError(f"parameter {name!r} is in groups {seen[name]} and {group}")
                seen[name] = group

    def groups(self) -> dict[str, Mapping[str, Param]]:
        """Group name -> its parameters, in the order of :data:`GROUPS`."""
        return {group: getattr(self, group) for group in GROUPS}

    @property
    def parameters(self) -> dict[str, Param]:
        """Every parameter, name -> :class:`Param`, group by group."""
        return {name: p for params in self.groups().values() for name, p in params.items()}

    def group_of(self, name: str) -> str:
        """The group of the parameter ``name``."""
        return next(group for group, params in self.groups().items() if name in params)

    def record(self, params: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
        """The kernel's settings of resolved ``params``: group -> field -> plain Python number
        (:func:`kernel_settings` of each group)."""
        return {group: kernel_settings(spec, params) for group, spec in self.groups().items()}


def with_default(param: Param, default: Any, note: str = "") -> Param:
    """``param`` with another default (and a note appended to its doc), same validation
    and kernel fields."""
    return replace(param, default=default, doc=param.doc + (f" ({note})" if note else ""))


#: Upper bound of the counts that scale with a scan (points, votes): the most beams a
#: reader accepts by default.
MAX_COUNT = 1_000_000
#: Upper bound of lengths and distances, metres (far beyond any laser's range).
MAX_METRES = 1e6
#: Bound of a number parameter that declares no narrower one: far beyond any distance
#: (m), multiple of a noise sigma or chi-square that means anything.
MAX_NUMBER = 1e6
#: Upper bound of a count of scans (a setting "after so many scans"; 1e12 scans is 30 years
#: of a laser at 1 kHz, so a caller may give it to mean "never").
MAX_SCANS = 10**12


def _real(name: str, value: Any, kind: str = "a number") -> float:
    """``value`` as a finite float (strings from the command line are parsed)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real | str):
        raise ParameterError(f"{name} must be {kind}, got {quote(value)}")
    try:
        out = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} must be {kind}, got {quote(value)}") from None
    if not math.isfinite(out):
        raise ParameterError(f"{name} must be a finite number, got {quote(value)}")
    return out


@dataclass(frozen=True, slots=True)
class Number(Check):
    """A finite real number in ``[low, high]`` (``(low, high]`` when ``low_open``)."""

    low: float = -MAX_NUMBER
    high: float = MAX_NUMBER
    low_open: bool = False

    def __call__(self, name: str, value: Any) -> float:
        out = _real(name, value)
        below = out <= self.low if self.low_open else out < self.low
        if below or out > self.high:
            raise ParameterError(f"{name} must be {self.describe()}, got {quote(value)}")
        return out

    def domain(self) -> dict[str, Any]:
        return {"type": "float", "low": self.low, "high": self.high, "low_open": self.low_open}

    def describe(self) -> str:
        bracket = "(" if self.low_open else "["
        return f"a number in {bracket}{self.low:g}, {self.high:g}]"


@dataclass(frozen=True, slots=True)
class Integer(Check):
    """An integer in ``[low, high]`` (a float with an integral value, or a string, is
    accepted)."""

    low: int
    high: int

    def __call__(self, name: str, value: Any) -> int:
        if isinstance(value, str):
            text = value.strip()
            try:
                value = int(text)
            except ValueError:
                value = _real(name, text, "an integer")
        elif not isinstance(value, int) or isinstance(value, bool):
            real = _real(name, value, "an integer")
            if isinstance(value, bool) or not real.is_integer():
                raise ParameterError(f"{name} must be an integer, got {quote(value)}")
            value = real
        if isinstance(value, float):
            if not value.is_integer():
                raise ParameterError(f"{name} must be an integer, got {quote(value)}")
            value = int(value)
        if not self.low <= value <= self.high:
            raise ParameterError(f"{name} must be {self.describe()}, got {quote(value)}")
        return int(value)

    def domain(self) -> dict[str, Any]:
        return {"type": "int", "low": self.low, "high": self.high}

    def describe(self) -> str:
        return f"an integer in [{self.low}, {self.high}]"


@dataclass(frozen=True, slots=True)
class Choice(Check):
    """One of ``options`` (strings are compared case-sensitively; ``"true"``/``"1"``
    select ``True``)."""

    options: tuple[Any, ...]

    def __call__(self, name: str, value: Any) -> Any:
        for option in self.options:
            if value == option and type(value) is type(option):
                return option
        if isinstance(value, str):
            lowered = value.strip().lower()
            for option in self.options:
                if isinstance(option, bool) and lowered in ("true", "false", "1", "0"):
                    if (lowered in ("true", "1")) == option:
                        return option
                elif str(option) == lowered:
                    return option
        raise ParameterError(f"{name} must be {self.describe()}, got {quote(value)}")

    def domain(self) -> dict[str, Any]:
        return {"type": "choice", "choices": list(self.options)}

    def describe(self) -> str:
        return "one of " + ", ".join(repr(o) for o in self.options)


@dataclass(frozen=True, slots=True)
class Either(Check):
    """A word (``"auto"``, ``None``...) or a value of ``inner``."""

    inner: Check
    words: tuple[str, ...]
    value: Any

    def __call__(self, name: str, value: Any) -> Any:
        if value is self.value or (isinstance(value, str) and value.strip().lower() in self.words):
            return self.value
        return self.inner(name, value)

    def domain(self) -> dict[str, Any]:
        return {**self.inner.domain(), "or": self.value}

    def describe(self) -> str:
        return f"{self.value!r} or {self.inner.describe()}"


@dataclass(frozen=True, slots=True)
class Pair(Check):
    """Two numbers ``(a, b)`` of ``element`` with ``a < b``; a string "a,b" is accepted."""

    element: Number

    def __call__(self, name: str, value: Any) -> tuple[float, float]:
        if isinstance(value, str):
            value = [part for part in value.replace("(", "").replace(")", "").split(",") if part]
        try:
            first, second = value
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be a pair (a, b), got {quote(value)}") from None
        a, b = self.element(name, first), self.element(name, second)
        if not a < b:
            raise ParameterError(f"{name} must have a < b, got {quote(value)}")
        return (a, b)

    def domain(self) -> dict[str, Any]:
        return {"type": "pair", "element": self.element.domain()}

    def describe(self) -> str:
        return f"a pair a < b, each {self.element.describe()}"


def number(*, low: float = -MAX_NUMBER, high: float = MAX_NUMBER, low_open: bool = False) -> Number:
    """A finite real number in ``[low, high]`` (``(low, high]`` when ``low_open``)."""
    return Number(low, high, low_open)


def integer(low: int, high: int) -> Integer:
    """An integer in ``[low, high]``."""
    return Integer(low, high)


def choice(*options: Any) -> Choice:
    """One of ``options``."""
    return Choice(options)


def optional(inner: Check, *, none_words: tuple[str, ...] = ("none", "off")) -> Either:
    """``None`` (or one of ``none_words`` as a string) or a value accepted by ``inner``."""
    return Either(inner, none_words, None)


def auto_or(inner: Check) -> Either:
    """The string ``"auto"`` or a value accepted by ``inner``."""
    return Either(inner, ("auto",), "auto")


def float_pair(*, low: float = 0.0, high: float = MAX_NUMBER) -> Pair:
    """Two finite numbers ``(a, b)`` with ``low <= a < b <= high``."""
    return Pair(Number(low, high))


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
        For an unknown preset or parameter (listing the valid ones) or a bad value; its
        ``parameter`` names the (first unknown) parameter, ``None`` for the preset.
    """
    values = {name: p.default for name, p in spec.items()}
    if preset is not None:
        if preset not in presets:
            valid = ", ".join(sorted(presets)) or "none"
            raise ParameterError(
                f"unknown preset {quote(preset)} for method {quote(method)}; valid: {valid}"
            )
        values.update(presets[preset])
    unknown = sorted(map(str, set(overrides) - set(spec)))
    if unknown:
        valid = ", ".join(sorted(spec))
        raise ParameterError(
            f"unknown parameter(s) {clip(', '.join(unknown), 160)} for method {quote(method)}; "
            f"valid: {valid}",
            parameter=unknown[0],
        )
    values.update(overrides)
    return {name: _checked(spec[name], name, value) for name, value in values.items()}


def _checked(param: Param, name: str, value: Any) -> Any:
    """``value`` checked by ``param``; an error names the parameter."""
    try:
        return param.check(name, value)
    except ParameterError as error:
        raise ParameterError(str(error), parameter=name) from None


def _given(value: Any, scale: float = 1.0) -> float:
    """A number, ``"auto"`` as NaN (not given) and ``None`` as inf (no bound)."""
    if value == "auto":
        return math.nan
    return math.inf if value is None else float(value * scale)


def as_float(name: str = "") -> KernelField:
    """A float field of a number parameter (``"auto"``: NaN, ``None``: inf)."""
    return KernelField(name, _given)


def radians(name: str = "") -> KernelField:
    """A field of an angle parameter in degrees, in radians (``"auto"``: NaN)."""
    return KernelField(name, lambda value: _given(value, math.pi / 180.0))


def coded(codes: Mapping[Any, int], name: str = "") -> KernelField:
    """A field of a choice, as its code."""
    return KernelField(name, lambda value: int(codes[value]))


def flag(name: str, when: Any) -> KernelField:
    """A boolean field ``name``: whether the value is ``when`` (``"auto"``, ``None``...)."""
    return KernelField(name, lambda value: bool(value == when))


def _implied_field(check: Check) -> KernelField:
    """The field a check implies: a number (``"auto"``: NaN, ``None``: inf), an integer or a
    boolean choice, under the parameter's name."""
    inner = check.inner if isinstance(check, Either) else check
    if isinstance(inner, Number):
        return as_float()
    if isinstance(check, Integer):
        return KernelField("", int)
    if isinstance(check, Choice) and all(isinstance(o, bool) for o in check.options):
        return KernelField("", bool)
    raise TypeError(f"declare the kernel fields of a parameter of {check.describe()}")


def kernel_settings(spec: Mapping[str, Param], params: Mapping[str, Any]) -> dict[str, Any]:
    """The fields of a kernel's settings record, name -> plain Python number, as the parameters of
    ``spec`` declare them (in their order), of the resolved ``params``."""
    out: dict[str, Any] = {}
    for name, param in spec.items():
        fields = (_implied_field(param.check),) if param.kernel is None else param.kernel
        for kernel_field in fields:
            out[kernel_field.name or name] = kernel_field.encode(params[name])
    return out


def param_lines(rows: list[tuple[str, str, Any, str, str]], what: str = "parameters") -> list[str]:
    """Parameters as the lines of a table, group by group: ``rows`` of ``(group, name,
    default, allowed values, doc)`` (:func:`~scanlines.method_info`, :class:`SettingsTable`)."""
    width = max((len(name) for _, name, *_ in rows), default=0)
    lines = [f"{what} (default; allowed values):"]
    shown = ""
    for group, name, default, allowed, doc in rows:
        if group != shown:
            shown = group
            lines.append(f" {group}:")
        lines.append(f"  {name:<{width}}  {default!r}; {allowed}")
        lines.append(f"  {'':<{width}}  {doc}")
    return lines
