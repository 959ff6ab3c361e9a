"""Settings tables: the settings of a stage that is not a method, declared as params groups."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import FrozenInstanceError
from typing import TYPE_CHECKING, Any, ClassVar, Self

from scanlines.errors import ParameterError
from scanlines.params import Param, kernel_settings, param_lines
from scanlines.untrusted import clip

__all__ = ["Groups", "SettingsTable"]

Groups = Mapping[str, Mapping[str, Param]]
"""A settings table's groups: group name -> setting name -> its :class:`~scanlines.params.Param`."""


class SettingsTable:
    """A frozen table of settings declared once, as :class:`~scanlines.params.Param` entries
    in named groups: the settings of a stage that is not an extraction method (map fusion,
    tracking, scan registration...).

    A subclass declares ``groups``: group name -> setting name -> ``Param`` (a name in one
    group only; the order of declaration is the order of :meth:`to_dict`)::

        class FusionSettings(SettingsTable):
            groups: ClassVar[Groups] = {
                "association": {"max_gap": Param(0.5, number(low=0.0), "... (m)"), ...},
                "support": {...},
            }

    and gets what a method's :class:`~scanlines.params.Settings` give its parameters:
    keyword construction from the defaults (``FusionSettings(min_scans=1)``); every value
    given checked by its ``Param`` (an unknown name or a bad value is a one-line
    :class:`~scanlines.ParameterError` naming the setting, ``FusionSettings.min_scans must
    be an integer in [1, ...], got 0``); the settings as attributes
    (``settings.min_scans``); :meth:`to_dict` (name -> value, what outputs record);
    :meth:`replace`; :meth:`describe`, the table appended to the class's docstring; and
    :meth:`record`, one record per group of the fields its parameters declare
    (:func:`~scanlines.params.kernel_settings`), which a compiled kernel's binding reads by
    name as it reads a method's. A subclass checks relations between its settings in
    :meth:`check`. Instances are immutable, hashable and compare by value.
    """

    groups: ClassVar[Groups] = {}
    #: Every setting, name -> its ``Param``, group by group (from ``groups``).
    parameters: ClassVar[Mapping[str, Param]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "groups" in cls.__dict__:
            cls.parameters = _table_parameters(cls)
            cls.__doc__ = f"{(cls.__doc__ or '').rstrip()}\n\n{cls.describe()}\n"

    def __init__(self, **values: Any) -> None:
        kind = type(self).__name__
        unknown = sorted(map(str, set(values) - set(self.parameters)))
        if unknown:
            raise ParameterError(
                f"unknown setting(s) {clip(', '.join(unknown), 160)} of {kind}; "
                f"valid: {', '.join(self.parameters)}",
                parameter=unknown[0],
            )
        resolved = {name: param.default for name, param in self.parameters.items()}
        for name, value in values.items():  # the defaults were checked with the class
            try:
                resolved[name] = self.parameters[name].check(f"{kind}.{name}", value)
            except ParameterError as error:
                raise ParameterError(str(error), parameter=name) from None
        self.__dict__.update(resolved)
        self.check()

    if TYPE_CHECKING:

        def __getattr__(self, name: str) -> Any: ...

    def check(self) -> None:
        """Relations between the settings (a subclass's): a ``ParameterError`` naming one
        of them when they do not hold."""

    def require_at_most(self, name: str, bound: str) -> None:
        """The relation ``name <= bound`` between two settings (for :meth:`check`): a
        ``ParameterError`` naming ``name`` when it does not hold."""
        value, limit = self.__dict__[name], self.__dict__[bound]
        if value > limit:
            raise ParameterError(
                f"{type(self).__name__}.{name} must be at most {bound} ({limit:g}), got {value:g}",
                parameter=name,
            )

    def to_dict(self) -> dict[str, Any]:
        """The settings by name, group by group."""
        return {name: self.__dict__[name] for name in self.parameters}

    def replace(self, **changes: Any) -> Self:
        """A copy with the settings ``changes`` (checked)."""
        return type(self)(**{**self.to_dict(), **changes})

    def record(self) -> dict[str, dict[str, Any]]:
        """What a compiled kernel reads: group -> field -> plain Python number, as the
        parameters declare their fields (:func:`~scanlines.params.kernel_settings`)."""
        return {group: kernel_settings(spec, self.__dict__) for group, spec in self.groups.items()}

    @classmethod
    def describe(cls) -> str:
        """The settings as :func:`~scanlines.method_info` prints a method's parameters:
        group by group, each with its default, allowed values and doc."""
        rows = [
            (group, name, param.default, param.check.describe(), param.doc)
            for group, params in cls.groups.items()
            for name, param in params.items()
        ]
        return "\n".join(param_lines(rows, "settings"))

    def __setattr__(self, name: str, value: Any) -> None:
        raise FrozenInstanceError(f"{type(self).__name__} is frozen: use replace({name}=...)")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"{type(self).__name__} is frozen")

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={value!r}" for name, value in self.to_dict().items())
        return f"{type(self).__name__}({shown})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return self.to_dict() == other.to_dict()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((type(self), tuple(self.to_dict().values())))


def _table_parameters(table: type[SettingsTable]) -> dict[str, Param]:
    """The settings of ``table``'s groups, name -> Param; a name in two groups, one that
    hides an attribute of the class, or a default its check does not return unchanged is
    a mistake of the declaration (TypeError)."""
    out: dict[str, Param] = {}
    for group, params in table.groups.items():
        for name, param in params.items():
            if name in out:
                raise TypeError(f"{table.__name__}: setting {name!r} is in two groups")
            if hasattr(table, name):
                raise TypeError(f"{table.__name__}: setting {name!r} hides an attribute")
            try:
                checked = param.check(f"{table.__name__}.{name}", param.default)
            except ParameterError as error:
                raise TypeError(f"{table.__name__}: {name}'s default: {error}") from None
            if type(checked) is not type(param.default) or checked != param.default:
                raise TypeError(f"{table.__name__}: declare {name}'s default as {checked!r}")
            out[name] = param
        if not params:
            raise TypeError(f"{table.__name__}: group {group!r} is empty")
    return out
