"""Extraction configurations: a method, a preset and the parameters the user set.

One :class:`ExtractionConfig` has four spellings that give it back exactly:

- a small TOML file (:meth:`ExtractionConfig.to_toml`, :func:`load_config`; ``--config
  FILE`` of ``scanlines run``, ``extract`` and ``eval``)::

      # scanlines extraction configuration
      method = "adaptive"
      preset = "paper"        # optional

      [params]
      min_points = 6
      dkth_range = [0.0, 0.05]   # written one number a line
      max_residual = "none"

- a dict for a JSON API (:meth:`ExtractionConfig.to_dict`,
  :meth:`ExtractionConfig.from_dict`);
- a command line (:meth:`ExtractionConfig.command`: ``scanlines run LOG --method ...
  --param NAME=VALUE``);
- the Python object itself (the parameters as :class:`~scanlines.Extractor` takes them).

Values are typed in a file or a dict: numbers are numbers (a float parameter takes an
integer too), choices are strings or booleans as the method lists them, a pair ``(a, b)``
is an array of two numbers, ``"auto"`` is the string ``"auto"`` and ``None`` is the string
``"none"`` (TOML has no null; a dict may also hold ``None``). On the command line every
value is a string that the parameter's check parses (``--param dkth_range=0.0,0.05``).

Every error is a :class:`ConfigError` (a :class:`~scanlines.ParameterError`) of one line
naming the file (or the ``source`` of a dict) and, where known, the line and the key.
"""

from __future__ import annotations

import numbers
import re
import shlex
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import tomli_w

from scanlines.builtin_methods import DEFAULT_METHOD
from scanlines.errors import NO_SUCH_FILE, ParameterError, describe, one_line
from scanlines.params import Check, Choice, Either, Integer, Number, Pair, resolve
from scanlines.untrusted import quote

__all__ = [
    "CONFIG_KEYS",
    "DEFAULT_METHOD",
    "ConfigError",
    "ExtractionConfig",
    "load_config",
]

#: The keys of a configuration (top-level keys of its TOML file, keys of its dict).
CONFIG_KEYS = ("method", "preset", "params")
#: Largest configuration file read: a configuration is a few lines; a log passed by
#: mistake is refused before it is read.
MAX_FILE_BYTES = 1 << 20
#: First line of a written configuration file.
HEADER = "# scanlines extraction configuration"


class ConfigError(ParameterError):
    """A configuration that cannot be read or is not valid.

    Parameters
    ----------
    message:
        What is wrong.
    source:
        The file (or what a dict came from), when known.
    line:
        The line of the file, when known.
    key:
        The key (``"method"``, ``"preset"``, ``"params.k"``...), when known.
    """

    def __init__(
        self,
        message: str,
        *,
        source: object | None = None,
        line: int | None = None,
        key: str | None = None,
    ) -> None:
        self.source = None if source is None else one_line(str(source))
        self.line = line
        self.key = key
        self.reason = one_line(message)
        where = [self.source] if self.source is not None else []
        if line is not None:
            where.append(f"line {line}")
        if key is not None:
            where.append(f"key {key}")
        super().__init__(f"{', '.join(where)}: {self.reason}" if where else self.reason)


@dataclass(frozen=True, repr=False)
class ExtractionConfig:
    """A method, an optional preset and parameter overrides, validated on construction.

    Parameters
    ----------
    method:
        A name from :func:`~scanlines.method_names`.
    preset:
        A preset of the method, or ``None``.
    params:
        Only the parameters the user set (overrides of the preset and the defaults),
        as :class:`~scanlines.Extractor` takes them. They are kept checked and typed
        (``"6"`` becomes ``6``, a pair a tuple of floats, ``"off"`` ``None``), in the
        order of the method's parameters, read-only.

    Raises
    ------
    ConfigError
        For an unknown method, preset or parameter, or a value outside its domain
        (the message names the key).
    """

    method: str = DEFAULT_METHOD
    preset: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._set(*_validated(self.method, self.preset, self.params, typed=False))

    @classmethod
    def _of_checked(cls, method: str, preset: str | None, params: dict[str, Any]):
        """The configuration of values :func:`_validated` gave (not validated again)."""
        config = object.__new__(cls)
        config._set(method, preset, params)
        return config

    def _set(self, method: str, preset: str | None, params: dict[str, Any]) -> None:
        object.__setattr__(self, "method", method)
        object.__setattr__(self, "preset", preset)
        object.__setattr__(self, "params", MappingProxyType(params))

    def __repr__(self) -> str:
        return (
            f"ExtractionConfig(method={self.method!r}, preset={self.preset!r}, "
            f"params={dict(self.params)!r})"
        )

    def __hash__(self) -> int:
        return hash((self.method, self.preset, tuple(self.params.items())))

    def __reduce__(self) -> tuple[Any, ...]:
        return ExtractionConfig, (self.method, self.preset, dict(self.params))

    def extractor(self, **kwargs: Any) -> Any:
        """The :class:`~scanlines.Extractor` of this configuration (``kwargs``:
        ``sensor_profile=...``)."""
        from scanlines.extractor import Extractor

        return Extractor(self.method, self.preset, **kwargs, **self.params)

    def resolved(self) -> dict[str, Any]:
        """Every parameter of the method as this configuration runs it (defaults, then
        the preset, then the overrides)."""
        return dict(self.extractor().params)

    # --------------------------------------------------------------- spellings

    def to_toml(self) -> str:
        """The configuration as a TOML file (what :func:`load_config` reads back equal)."""
        document: dict[str, Any] = {"method": self.method}
        if self.preset is not None:
            document["preset"] = self.preset
        checks = _checks(self.method)
        document["params"] = {name: _spelled(checks[name], v) for name, v in self.params.items()}
        return f"{HEADER}\n{tomli_w.dumps(document)}"

    def to_dict(self) -> dict[str, Any]:
        """``{"method": ..., "preset": ... or None, "params": {...}}`` as JSON holds it (a
        pair as a list, ``None`` as ``None``); :meth:`from_dict` reads it back equal."""
        return {
            "method": self.method,
            "preset": self.preset,
            "params": {name: _json_value(value) for name, value in self.params.items()},
        }

    @classmethod
    def from_dict(cls, mapping: Any, source: str = "configuration") -> ExtractionConfig:
        """The configuration of ``{"method": ..., "preset": ..., "params": {...}}`` (what
        :meth:`to_dict` gives, or a JSON request); ``method`` defaults to ``"adaptive"``,
        ``preset`` and ``params`` may be missing or ``None``. Values must have their
        type (a number, not a string of one); ``None`` or ``"none"`` is ``None``.

        Raises
        ------
        ConfigError
            Naming ``source`` and the key, for an unknown key, a value of the wrong
            type, an unknown method, preset or parameter, or a value outside its domain.
        """
        return _from_mapping(mapping, source)

    def cli_values(self) -> dict[str, str]:
        """Each parameter spelled as ``--param NAME=VALUE`` (or a method spec of
        ``scanlines eval``) takes it back: ``{"dkth_range": "0.0,0.05", ...}``."""
        checks = _checks(self.method)
        return {name: _cli_value(checks[name], value) for name, value in self.params.items()}

    def command(self, log: str = "LOG") -> str:
        """The ``scanlines run`` command line that runs this configuration on ``log``,
        every word quoted for a POSIX shell: ``scanlines run LOG --method adaptive
        --preset paper --param min_points=6``."""
        words = ["scanlines", "run", str(log), "--method", self.method]
        if self.preset is not None:
            words += ["--preset", self.preset]
        for name, value in self.cli_values().items():
            words += ["--param", f"{name}={value}"]
        return " ".join(shlex.quote(word) for word in words)


def load_config(path: str | Path) -> ExtractionConfig:
    """Read a configuration file (TOML; see :meth:`ExtractionConfig.to_toml`).

    Raises
    ------
    ConfigError
        One line naming the file (and the line and key, where known): a file that is
        missing or unreadable, not TOML (with the line of the syntax error), an
        unknown top-level key, a value of the wrong type, an unknown method, preset or
        parameter, or a value outside its domain.
    """
    path = Path(path)
    try:
        with path.open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(NO_SUCH_FILE, source=path) from None
    except OSError as error:
        reason = error.strerror or describe(error)
        raise ConfigError(f"cannot read the configuration: {reason}", source=path) from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(
            f"larger than {MAX_FILE_BYTES} bytes; a configuration is a small TOML file",
            source=path,
        )
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        raise ConfigError("not UTF-8 text (a TOML file is)", source=path, line=line) from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        message, line = _toml_error(str(error))
        raise ConfigError(f"not valid TOML: {message}", source=path, line=line) from None
    except RecursionError:  # tomllib reads nested arrays and tables recursively
        raise ConfigError(
            "not a configuration: arrays or tables nested too deep", source=path
        ) from None
    except ValueError as error:  # an integer of more digits than Python converts
        raise ConfigError(f"not a configuration: {describe(error)}", source=path) from None
    return _from_mapping(document, path, text)


# ------------------------------------------------------- where in a file a mistake is

_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)$")
_TOML_END = re.compile(r"\s*\(at end of document\)$")


def _toml_error(text: str) -> tuple[str, int | None]:
    """tomllib's message without its position, and the line it names."""
    match = _TOML_POSITION.search(text)
    if match:
        return f"{text[: match.start()]} (column {match.group(2)})", int(match.group(1))
    return _TOML_END.sub(" (at the end of the file)", text), None


def _line_of(text: str | None, key: str | None) -> int | None:
    """The line of the file ``text`` that sets ``key`` (``"method"``, ``"params.k"``),
    found by a plain scan of the lines (good for the files this module writes and what people
    write by hand), or ``None``."""
    if text is None or key is None:
        return None
    table, _, name = key.rpartition(".")
    quoted = rf"(?:{re.escape(name)}|\"{re.escape(name)}\"|'{re.escape(name)}')"
    assignment = re.compile(rf"\s*{quoted}\s*=")
    dotted = re.compile(rf"\s*{re.escape(table)}\s*\.\s*{quoted}\s*=") if table else None
    header = re.compile(r"\s*\[\s*([^\[\]]*?)\s*\]\s*(?:#.*)?$")
    current, table_line = "", None
    for number, line in enumerate(text.splitlines(), start=1):
        found = header.match(line)
        if found:
            current = found.group(1).strip("\"'")
            if current == key:
                return number
            if current == table:
                table_line = number
            continue
        if current == table and assignment.match(line):
            return number
        if current == "" and dotted is not None and dotted.match(line):
            return number
    return table_line


# ------------------------------------------------------------------- reading


def _from_mapping(mapping: Any, source: object, text: str | None = None) -> ExtractionConfig:
    """The configuration of a parsed TOML document or a dict; errors name ``source``
    (and, with the file's ``text``, the line of the key)."""

    def fail(message: str, key: str | None = None) -> ConfigError:
        return ConfigError(message, source=source, line=_line_of(text, key), key=key)

    if not isinstance(mapping, Mapping):
        raise fail(f"a configuration is a table of {', '.join(CONFIG_KEYS)}")
    for key in mapping:
        if key not in CONFIG_KEYS:
            raise fail(f"unknown key; valid: {', '.join(CONFIG_KEYS)}", str(key))
    params = mapping.get("params")
    if params is not None and not isinstance(params, Mapping):
        raise fail(f"params is a table of NAME = VALUE, got {quote(params)}", "params")
    method, preset = mapping.get("method", DEFAULT_METHOD), mapping.get("preset")
    try:
        return ExtractionConfig._of_checked(*_validated(method, preset, params, typed=True))
    except ConfigError as error:
        raise fail(error.reason, error.key) from None


def _validated(
    method: Any, preset: Any, params: Any, *, typed: bool
) -> tuple[str, str | None, dict[str, Any]]:
    """``(method, preset, params)`` checked, the values converted by their checks and in
    the method's order. ``typed``: every value must already have its type (a file or a
    JSON dict), not be a string that parses to it (a command line).

    Raises
    ------
    ConfigError
        Naming the key at fault.
    """
    from scanlines.methods import method_class

    if not isinstance(method, str):
        raise ConfigError(f"the method is a string, got {quote(method)}", key="method")
    try:
        cls = method_class(method)
    except ParameterError as error:
        raise ConfigError(str(error), key="method") from None
    if preset is not None and not isinstance(preset, str):
        raise ConfigError(f"the preset is a string, got {quote(preset)}", key="preset")
    if params is None:
        params = {}
    if not isinstance(params, Mapping):
        raise ConfigError(
            f"params is a mapping of names to values, got {quote(params)}", key="params"
        )
    if typed:
        _check_types(cls.parameters, params)
    try:
        resolved = resolve(method, cls.parameters, cls.presets, preset, params)
    except ParameterError as error:
        raise ConfigError(str(error), key=_key_of(error)) from None
    try:
        cls(resolved)  # what the method itself refuses
    except ParameterError as error:
        raise ConfigError(str(error)) from None
    return method, preset, {name: resolved[name] for name in cls.parameters if name in params}


def _key_of(error: ParameterError) -> str:
    """The key of a configuration that ``error`` of :func:`~scanlines.params.resolve`
    names: ``params.NAME``, else the preset."""
    return "preset" if error.parameter is None else f"params.{error.parameter}"


def _check_types(spec: Mapping[str, Any], params: Mapping[str, Any]) -> None:
    """That every value of a file or a dict has a type its check takes (see
    :func:`_type_fits`); unknown names are left to :func:`~scanlines.params.resolve`."""
    for name, value in params.items():
        if name not in spec:
            continue
        check = spec[name].check
        if not _type_fits(check, value):
            raise ConfigError(
                f"{name} must be {check.describe()}, got {quote(value)}{_type_hint(check, value)}",
                key=f"params.{name}",
            )


def _checks(method: str) -> dict[str, Check]:
    from scanlines.methods import method_class

    return {name: p.check for name, p in method_class(method).parameters.items()}


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _type_fits(check: Check, value: Any) -> bool:
    """Whether ``value`` of a file or a dict has a type ``check`` takes: numbers as
    numbers, pairs as arrays, strings only for choices and words (``"auto"``,
    ``"none"``). Unknown checks (a method registered elsewhere) decide alone."""
    if isinstance(check, Either):
        if value is check.value:
            return True
        if isinstance(value, str) and value.strip().lower() in check.words:
            return True
        return _type_fits(check.inner, value)
    if isinstance(check, Number | Integer):
        return _is_number(value)
    if isinstance(check, Pair):
        return isinstance(value, list | tuple) and all(_is_number(v) for v in value)
    if isinstance(check, Choice) and isinstance(value, str):
        return any(isinstance(option, str) for option in check.options)
    return True


def _type_hint(check: Check, value: Any) -> str:
    """What to write instead of a string where ``check`` wants a number, a pair or a
    boolean."""
    if not isinstance(value, str):
        return ""
    while isinstance(check, Either):
        check = check.inner
    if isinstance(check, Pair):
        return " (a string; a pair is an array: [a, b])"
    if isinstance(check, Choice):
        return " (a string; booleans are written true or false, without quotes)"
    return " (a string; numbers are written without quotes)"


# ------------------------------------------------------------------- writing


def _none_word(check: Check) -> str:
    """How ``None`` is spelled for ``check``: the first of its words (``"none"``)."""
    while isinstance(check, Either):
        if check.value is None and check.words:
            return check.words[0]
        check = check.inner
    return "none"


def _spelled(check: Check, value: Any) -> Any:
    """``value`` as a file holds it: ``None`` as its word, a pair as a list."""
    if value is None:
        return _none_word(check)
    if isinstance(value, tuple):
        return list(value)
    return value


def _cli_value(check: Check, value: Any) -> str:
    """``value`` as ``--param NAME=VALUE`` spells it (parsed back by ``check``)."""
    if value is None:
        return _none_word(check)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list | tuple):
        return ",".join(_cli_value(check, v) for v in value)
    return str(value)


def _json_value(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_json_value(v) for v in value]
    return value
