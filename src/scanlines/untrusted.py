"""What comes from outside (parameters files, sensor profiles, maps) read at a bounded cost.

A file a user names may be anything: a FIFO or ``/dev/zero`` (which never end), a log
passed by mistake, a YAML "billion laughs" whose aliases expand 454 bytes into a billion
nodes, 100 KB of nested ``[`` (which Python's recursive readers turn into a
``RecursionError``), an integer of 5,000 digits (which Python refuses to print). The
helpers here refuse each in one line (:class:`UntrustedInput`, which the callers turn into
their own error naming the file or the parameter):

- :func:`read_regular_file`: a regular file only, opened without blocking, at most
  ``limit`` bytes read;
- :func:`load_yaml`: YAML without recursive aliases, nested at most :data:`MAX_DEPTH` deep,
  at most :data:`MAX_NODES` nodes once aliases are expanded, integers of at most
  :data:`MAX_INTEGER_DIGITS` digits;
- :func:`load_json`: JSON nested at most :data:`MAX_DEPTH` deep;
- :func:`quote`: a value as an error message quotes it, at most :data:`QUOTED` characters
  (never the expansion of a huge or nested value); :func:`clip` a text the same way.
"""

from __future__ import annotations

import json
import math
import os
import re
import reprlib
import stat
from pathlib import Path
from typing import Any

from scanlines.errors import one_line

__all__ = [
    "MAX_DEPTH",
    "MAX_INTEGER_DIGITS",
    "MAX_NODES",
    "QUOTED",
    "UntrustedInput",
    "clip",
    "load_json",
    "load_yaml",
    "quote",
    "read_regular_file",
]

#: Most characters of a value an error message quotes.
QUOTED = 80
#: Deepest nesting of lists and mappings read (a parameters file nests three or four deep).
MAX_DEPTH = 64
#: Most YAML nodes of a document, each alias counted as the nodes it stands for.
MAX_NODES = 100_000
#: Most digits of a YAML integer (a parameter is at most a million).
MAX_INTEGER_DIGITS = 100


class UntrustedInput(ValueError):
    """Input refused before it costs more than it is worth; the message is one line
    without the file's name (the caller adds it)."""


# ----------------------------------------------------------------------------- quoting


class _ShortRepr(reprlib.Repr):
    """``reprlib``'s bounded repr, with integers too long to print named by their size."""

    def __init__(self) -> None:
        super().__init__()
        self.maxlevel = 3
        self.maxstring = QUOTED
        self.maxother = QUOTED
        self.maxlong = 40

    def repr_int(self, x: int, level: int) -> str:
        if x.bit_length() > 128:
            return f"<an integer of {integer_digits(x)} digits>"
        return super().repr_int(x, level)


_SHORT = _ShortRepr()


def integer_digits(x: int) -> int:
    """The number of decimal digits of ``x`` (from its bit length, without printing it)."""
    magnitude = abs(x)
    estimate = math.floor(magnitude.bit_length() * math.log10(2))  # the digits, or one more
    return estimate + 1 if magnitude >= 10**estimate else max(estimate, 1)


def quote(value: Any, limit: int = QUOTED) -> str:
    """``repr(value)`` on one line, at most ``limit`` characters (``...`` where cut); a
    nested or huge value is never expanded whole."""
    if isinstance(value, str):
        text = repr(value[: limit + 1])
    else:
        try:
            text = _SHORT.repr(value)
        except Exception:  # a foreign object whose repr fails
            text = f"<{type(value).__name__}>"
    text = one_line(text)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def clip(text: str, limit: int = QUOTED) -> str:
    """``text`` on one line, at most ``limit`` characters (``...`` where cut)."""
    text = one_line(text[: 4 * limit])
    return text if len(text) <= limit else text[: limit - 3] + "..."


# ------------------------------------------------------------------------------- files


def read_regular_file(path: str | Path, limit: int) -> bytes:
    """The bytes of the regular file ``path``, of at most ``limit`` bytes.

    Raises
    ------
    UntrustedInput
        For a FIFO, a device (``/dev/zero``), a socket or a directory, or a file larger
        than ``limit`` bytes (only ``limit + 1`` bytes are read).
    OSError
        When the file cannot be opened or read (missing, not readable).
    """
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # a FIFO must not block
    with os.fdopen(descriptor, "rb") as handle:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise UntrustedInput(f"not a regular file ({_file_kind(mode)})")
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise UntrustedInput(f"larger than {limit} bytes")
    return data


def _file_kind(mode: int) -> str:
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a file")


# -------------------------------------------------------------------------------- YAML


def _yaml_loader() -> type:
    import yaml

    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def load_yaml(data: str | bytes) -> Any:
    """``yaml.safe_load(data)`` once the document has been found bounded (module
    docstring); its first document.

    Raises
    ------
    UntrustedInput
        A recursive alias, a nesting deeper than :data:`MAX_DEPTH`, more than
        :data:`MAX_NODES` nodes with aliases expanded, or an integer of more than
        :data:`MAX_INTEGER_DIGITS` digits.
    yaml.YAMLError
        For text that is not YAML.
    """
    import yaml

    check_yaml_events(yaml.parse(data, Loader=_yaml_loader()))
    return yaml.load(data, Loader=_yaml_loader())  # a safe loader


def check_yaml_events(events: Any) -> None:
    """Walk YAML ``events`` (``yaml.parse``) once, refusing what :func:`load_yaml` refuses:
    each anchored node's size is noted when it closes, so an alias counts as the nodes it
    stands for without being expanded."""
    import yaml
    from yaml.resolver import Resolver

    resolver = Resolver()
    sizes: dict[str, int] = {}
    frames: list[list[Any]] = [[None, 0]]  # [anchor of the open collection, nodes in it]
    for event in events:
        if isinstance(event, yaml.CollectionStartEvent):
            if len(frames) > MAX_DEPTH:
                raise UntrustedInput(f"nested more than {MAX_DEPTH} deep")
            frames.append([event.anchor, 1])
            continue
        if isinstance(event, yaml.CollectionEndEvent):
            anchor, size = frames.pop()
            if anchor is not None:
                sizes[anchor] = size
        elif isinstance(event, yaml.AliasEvent):
            if event.anchor not in sizes:
                open_anchors = {frame[0] for frame in frames}
                if event.anchor in open_anchors:
                    raise UntrustedInput(f"a recursive alias (*{event.anchor} inside itself)")
                continue  # an undefined alias: the loader names it
            size = sizes[event.anchor]
        elif isinstance(event, yaml.ScalarEvent):
            _check_scalar(event, resolver)
            size = 1
            if event.anchor is not None:
                sizes[event.anchor] = 1
        else:
            continue
        frames[-1][1] += size
        if frames[-1][1] > MAX_NODES:
            raise UntrustedInput(f"more than {MAX_NODES} values once its aliases are expanded")


def _check_scalar(event: Any, resolver: Any) -> None:
    """Refuse a plain integer of more than :data:`MAX_INTEGER_DIGITS` digits."""
    import yaml

    value = event.value
    if len(value) <= MAX_INTEGER_DIGITS or event.style not in (None, ""):
        return
    if event.tag not in (None, "!"):
        tag = event.tag
    else:
        tag = resolver.resolve(yaml.ScalarNode, value, event.implicit)
    if tag == "tag:yaml.org,2002:int":
        raise UntrustedInput(
            f"an integer of {len(value)} characters (at most {MAX_INTEGER_DIGITS} digits)"
        )


# -------------------------------------------------------------------------------- JSON


def load_json(text: str | bytes) -> Any:
    """``json.loads(text)``, nesting at most :data:`MAX_DEPTH` deep.

    Raises
    ------
    UntrustedInput
        For a deeper nesting (checked before parsing: Python's reader is recursive).
    json.JSONDecodeError
        For text that is not JSON.
    """
    if isinstance(text, bytes):
        text = text.decode("utf-8")
    depth = json_depth(text)
    if depth > MAX_DEPTH:
        raise UntrustedInput(f"nested more than {MAX_DEPTH} deep")
    return json.loads(text)


def json_depth(text: str) -> int:
    """The deepest nesting of ``[`` and ``{`` in JSON ``text``, strings skipped (regular
    expressions and numpy: linear, at C speed; malformed text is left to the parser)."""
    import numpy as np

    brackets = _NOT_BRACKET.sub("", _JSON_STRING.sub("", text)).encode("ascii")
    if not brackets:
        return 0
    codes = np.frombuffer(brackets, dtype=np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1)
    return int(np.cumsum(steps).max())


_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
_NOT_BRACKET = re.compile(r"[^\[\]{}]+")
