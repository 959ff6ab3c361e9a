"""Method specs: which method, preset and parameters a row of the evaluation runs.

A spec names a method, optionally a preset, parameter overrides and a label::

    METHOD[:PRESET][?NAME=VALUE[&NAME=VALUE]...][@LABEL]

``adaptive``, ``adaptive:paper``, ``adaptive?k=4&fit=paper``,
``adaptive:paper?k=4@paper-k4``. Values are validated by the method (a pair is
written ``dkth_range=0,0.05``). The label defaults to the spec text without the
label; labels must be unique within a run.

The spec ``truth`` (optionally ``truth@LABEL``; no preset or parameters) is not a
method but a reference row (:data:`TRUTH`, built by
:func:`scanlines.evaluation.truth_row.truth_extraction`); it has no extractor.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from scanlines import Extractor, ParameterError
from scanlines.report import jsonable
from scanlines.sensor.profile import SensorProfile

__all__ = ["TRUTH", "MethodSpec", "parse_spec", "parse_specs"]

TRUTH = "truth"
"""Spec name of the truth row (see :mod:`scanlines.evaluation.truth_row`); not a method."""


@dataclass(frozen=True)
class MethodSpec:
    """One configuration of one method, and its label in the results.

    Attributes
    ----------
    method:
        A name from :func:`scanlines.method_names`, or :data:`TRUTH` for the truth row.
    preset:
        A preset of the method, or ``None``.
    params:
        ``(name, value)`` overrides in the order given (values as written).
    label:
        Name of this configuration in tables, files and figures; the spec text
        (:attr:`text`) when empty.
    """

    method: str
    preset: str | None = None
    params: tuple[tuple[str, Any], ...] = ()
    label: str = ""

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", self.text)

    @property
    def text(self) -> str:
        """The spec without its label: ``METHOD[:PRESET][?NAME=VALUE&...]``."""
        preset = f":{self.preset}" if self.preset else ""
        query = "&".join(f"{k}={v}" for k, v in self.params)
        return f"{self.method}{preset}{'?' + query if query else ''}"

    @property
    def params_text(self) -> str:
        """The overrides as ``NAME=VALUE&...`` (empty without overrides)."""
        return "&".join(f"{k}={v}" for k, v in self.params)

    @property
    def is_truth(self) -> bool:
        """Whether this is the truth row (:data:`TRUTH`), not a method."""
        return self.method == TRUTH

    def extractor(self, sensor_profile: SensorProfile | None = None) -> Extractor:
        """The configured :class:`~scanlines.Extractor` (validates the spec), with
        ``sensor_profile`` when given.

        Raises
        ------
        ParameterError
            For the truth row, which has no extractor (it needs the truth).
        """
        if self.is_truth:
            raise ParameterError(f"{TRUTH!r} is built from the truth and has no extractor")
        return Extractor(
            self.method, self.preset, sensor_profile=sensor_profile, **dict(self.params)
        )

    def to_dict(self) -> dict[str, Any]:
        """Label, method, preset, overrides and the full resolved parameters."""
        return {
            "label": self.label,
            "spec": self.text,
            "method": self.method,
            "preset": self.preset,
            "params": dict(self.params),
            "resolved": {}
            if self.is_truth
            else {k: jsonable(v) for k, v in self.extractor().params.items()},
        }


def parse_spec(text: str) -> MethodSpec:
    """Parse ``METHOD[:PRESET][?NAME=VALUE[&NAME=VALUE]...][@LABEL]`` and validate it.

    Raises
    ------
    ParameterError
        For bad syntax, or an unknown method, preset or parameter, or a bad value
        (the message starts with the spec).
    """
    try:
        spec = _split_spec(text.strip())
        _check_spec(spec)
    except ParameterError as error:
        raise ParameterError(f"method spec {text!r}: {error}") from None
    return spec


def _split_spec(text: str) -> MethodSpec:
    body, at, label = text.partition("@")
    if at and not label.strip():
        raise ParameterError("empty label after '@'")
    head, question, query = body.partition("?")
    method, colon, preset = head.partition(":")
    if not method.strip():
        raise ParameterError("no method name")
    if colon and not preset.strip():
        raise ParameterError("empty preset after ':'")
    if question and not query.strip():
        raise ParameterError("no NAME=VALUE after '?'")
    params = _split_query(query) if question else ()
    return MethodSpec(method.strip(), preset.strip() or None, params, label.strip())


def _split_query(query: str) -> tuple[tuple[str, str], ...]:
    pairs: list[tuple[str, str]] = []
    for part in query.split("&"):
        name, eq, value = part.partition("=")
        if not eq or not name.strip() or not value.strip():
            raise ParameterError(f"parameters are NAME=VALUE joined by '&', got {part!r}")
        pairs.append((name.strip(), value.strip()))
    names = [name for name, _ in pairs]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ParameterError(f"parameter(s) given twice: {', '.join(repeated)}")
    return tuple(pairs)


def parse_specs(specs: Iterable[str | MethodSpec]) -> tuple[MethodSpec, ...]:
    """Parse (and validate) several specs; labels must be unique.

    Raises
    ------
    ParameterError
        For a bad spec, no spec at all, or a label used twice.
    """
    parsed = tuple(_validated(s) if isinstance(s, MethodSpec) else parse_spec(s) for s in specs)
    if not parsed:
        raise ParameterError("give at least one method spec")
    labels = [s.label for s in parsed]
    repeated = sorted({label for label in labels if labels.count(label) > 1})
    if repeated:
        raise ParameterError(
            f"method label(s) used twice: {', '.join(repeated)}; add '@LABEL' to tell them apart"
        )
    return parsed


def _validated(spec: MethodSpec) -> MethodSpec:
    try:
        _check_spec(spec)
    except ParameterError as error:
        raise ParameterError(f"method spec {spec.text!r}: {error}") from None
    return spec


def _check_spec(spec: MethodSpec) -> None:
    if not spec.is_truth:
        spec.extractor()
    elif spec.preset or spec.params:
        raise ParameterError(f"{TRUTH!r} takes no preset or parameters")
