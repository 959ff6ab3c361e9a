"""Seeded mutators of the files that set things: parameters files (YAML), configurations
(TOML), sensor profiles and line maps (JSON).

Text mutators replace one value (a ``name: value`` or ``name = value`` line) with a hostile
one: non-finite and extreme numbers, booleans where numbers go, integers of 30 to 5,000
digits, strings of up to 100,000 characters, nesting 63 to 100,000 deep, recursive and
undefined aliases, Python tags; or add a YAML alias bomb (2 to 9 levels of 9) referenced by
a parameter. JSON mutators parse the document, set one leaf (or one line's field, or
every line's) to such a value, drop a key or add one, and write it back (raw text where
JSON has no spelling: digits beyond a double, deep nesting); map mutators also move a
line's ends off its ``(rho, alpha)``, or give covariances of another shape, sign or
symmetry. ``mutate.py``'s line and byte mutators apply too (``file_target.py``).
"""

from __future__ import annotations

import json
import random
import re

from .mutate import Mutator

#: Values a YAML parameter is set to (raw YAML).
YAML_VALUES = (
    ".nan", ".inf", "-.inf", "1e308", "-1e308", "5e-324", "1e-46", "0", "-1", "true", "null",
    "~", "[]", "{}", "[1, 2, 3]", "''", "*undefined", "&a [*a]", "&a {k: *a}",
    "!!python/object/apply:os.system ['true']", "!!binary aGVsbG8=", "2001-12-14",
    "0x7fffffffffffffff", "1_000_000", "190:20:30",
)  # fmt: skip
#: Values a TOML parameter is set to (raw TOML).
TOML_VALUES = (
    "nan", "inf", "-inf", "1e308", "-1e308", "5e-324", "0", "-1", "true", "[]", "{}",
    "[1, 2, 3]", "''", "0x7fffffffffffffff", "1979-05-27", "'none'", "'auto'",
)  # fmt: skip
#: JSON values a leaf is set to (written with ``json.dumps``, NaN and Infinity included).
JSON_VALUES = (
    float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 5e-324, 0, -1, True, False,
    None, [], {}, [1.0], [1.0, 2.0, 3.0], "", "nan", "inf", "x", 2**64, -(2**63),
)  # fmt: skip
DIGITS = (30, 101, 400, 4300, 4301, 5000)
LENGTHS = (81, 1000, 100_000)
DEPTHS = (63, 64, 65, 1000, 100_000)
VALUE_LINE = re.compile(rb"^(\s*[^\s#:=][^:=]*?\s*(?::|=)\s*)(\S.*)$")


def hostile_text(rng: random.Random, values: tuple[str, ...], quote: str) -> str:
    """A raw value: one of ``values``, a long integer, a long string or deep nesting."""
    kind = rng.randrange(5)
    if kind == 0:
        return rng.choice(("", "-")) + "9" * rng.choice(DIGITS)
    if kind == 1:
        return quote + "x" * rng.choice(LENGTHS) + quote
    if kind == 2:
        depth = rng.choice(DEPTHS)
        return "[" * depth + "1" + "]" * depth * rng.randrange(2)
    return rng.choice(values)


def replace_value(values: tuple[str, ...], quote: str) -> Mutator:
    """Set the value of one ``name: value`` (``name = value``) line to a hostile one."""

    def mutate(rng: random.Random, data: bytes) -> bytes:
        lines = data.split(b"\n")
        candidates = [k for k, line in enumerate(lines) if VALUE_LINE.match(line)]
        if not candidates:
            return data
        k = rng.choice(candidates)
        match = VALUE_LINE.match(lines[k])
        assert match is not None
        lines[k] = match.group(1) + hostile_text(rng, values, quote).encode()
        return b"\n".join(lines)

    return mutate


def alias_bomb(rng: random.Random, data: bytes) -> bytes:
    """Anchors of 9 strings nested 2 to 9 levels in another node's section, the last
    referenced by one of this file's parameters."""
    levels = rng.randint(2, 9)
    names = "abcdefghij"
    rows = ['    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for k in range(1, levels):
        rows.append(f"    {names[k]}: &{names[k]} [{','.join(['*' + names[k - 1]] * 9)}]")
    bomb = ("other_node:\n  ros__parameters:\n" + "\n".join(rows) + "\n").encode()
    lines = data.split(b"\n")
    candidates = [k for k, line in enumerate(lines) if VALUE_LINE.match(line)]
    if candidates:
        k = rng.choice(candidates)
        match = VALUE_LINE.match(lines[k])
        assert match is not None
        lines[k] = match.group(1) + f"*{names[levels - 1]}".encode()
    return bomb + b"\n".join(lines)


YAML_MUTATORS: dict[str, Mutator] = {
    "yaml_value": replace_value(YAML_VALUES, "'"),
    "alias_bomb": alias_bomb,
}
TOML_MUTATORS: dict[str, Mutator] = {"toml_value": replace_value(TOML_VALUES, '"')}

# -- JSON -----------------------------------------------------------------------------------

PLACEHOLDER = "@@raw@@"


def _dump(document: object, raw: str | None) -> bytes:
    """``document`` as JSON, its placeholder string replaced by the raw text ``raw``."""
    text = json.dumps(document)
    if raw is not None:
        text = text.replace(json.dumps(PLACEHOLDER), raw, 1)
    return text.encode()


def _leaves(node: object, path: tuple = ()) -> list[tuple]:
    """The paths to every value of a JSON document (containers included)."""
    found = [path] if path else []
    if isinstance(node, dict):
        for key, value in node.items():
            found += _leaves(value, (*path, key))
    elif isinstance(node, list):
        for k, value in enumerate(node[:50]):
            found += _leaves(value, (*path, k))
    return found


def _hostile_json(rng: random.Random) -> tuple[object, str | None]:
    """A value for a JSON leaf and, for values JSON cannot spell, its raw text."""
    kind = rng.randrange(6)
    if kind == 0:
        return PLACEHOLDER, rng.choice(("", "-")) + "9" * rng.choice(DIGITS)
    if kind == 1:
        depth = rng.choice(DEPTHS)
        return PLACEHOLDER, "[" * depth + "]" * depth
    if kind == 2:
        return "x" * rng.choice(LENGTHS), None
    return rng.choice(JSON_VALUES), None


def _set(document: object, path: tuple, value: object) -> None:
    node = document
    for key in path[:-1]:
        node = node[key]  # type: ignore[index]
    node[path[-1]] = value  # type: ignore[index]


def json_edit(edit) -> Mutator:
    """A mutator editing the parsed document (``edit(rng, document)`` returns the raw text
    of its placeholder, or None); a document that no longer parses is left as it is."""

    def mutate(rng: random.Random, data: bytes) -> bytes:
        try:
            document = json.loads(data)
        except ValueError:
            return data
        raw = edit(rng, document)
        return _dump(document, raw)

    return mutate


def _leaf_value(rng: random.Random, document: object) -> str | None:
    paths = _leaves(document)
    if not paths:
        return None
    value, raw = _hostile_json(rng)
    _set(document, rng.choice(paths), value)
    return raw


def _drop_key(rng: random.Random, document: object) -> None:
    paths = [p for p in _leaves(document) if isinstance(p[-1], str)]
    if paths:
        path = rng.choice(paths)
        node = document
        for key in path[:-1]:
            node = node[key]  # type: ignore[index]
        del node[path[-1]]  # type: ignore[attr-defined]


def _add_key(rng: random.Random, document: object) -> None:
    if isinstance(document, dict):
        document[rng.choice(("extra", "k" * 1000, "format2", ""))] = rng.choice(JSON_VALUES)


def _lines_of(document: object) -> list:
    lines = document.get("lines") if isinstance(document, dict) else None
    return lines if isinstance(lines, list) and lines else []


def _line_field(rng: random.Random, document: object) -> str | None:
    """One field of one map line (or of every line) set to a hostile value."""
    lines = _lines_of(document)
    if not lines:
        return None
    name = rng.choice(("start", "end", "rho", "alpha", "covariance"))
    value, raw = _hostile_json(rng)
    if raw is None and rng.random() < 0.3:
        for line in lines:
            if isinstance(line, dict):
                line[name] = value
        return None
    line = rng.choice(lines)
    if isinstance(line, dict):
        line[name] = value
    return raw


def _move_end(rng: random.Random, document: object) -> None:
    """A line's end moved (off its line, or far): its rho and alpha left as they were."""
    lines = [line for line in _lines_of(document) if isinstance(line, dict)]
    if lines:
        line = rng.choice(lines)
        end = line.get(rng.choice(("start", "end")))
        if isinstance(end, list) and len(end) == 2 and all(isinstance(v, float) for v in end):
            end[rng.randrange(2)] += rng.choice((1e-4, 0.01, 1.0, 1e5, 1e9, 1e300))


def _covariance(rng: random.Random, document: object) -> None:
    lines = [line for line in _lines_of(document) if isinstance(line, dict)]
    shapes = (
        [[1.0, 0.0], [0.0, -1.0]], [[1.0, 2.0], [2.0, 1.0]], [[1.0, 0.5], [0.1, 1.0]],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [[1.0]], [1.0, 2.0], 1.0,
        [[True, False], [False, True]], [[1e308, 1e308], [1e308, 1e308]], [[0.0, 0.0], [0.0, 0.0]],
    )  # fmt: skip
    if lines:
        rng.choice(lines)["covariance"] = rng.choice(shapes)


def _origin(rng: random.Random, document: object) -> None:
    frame = document.get("frame") if isinstance(document, dict) else None
    if isinstance(frame, dict):
        frame["origin"] = rng.choice(
            ([float("nan"), 0.0], [1e9 + 1, 0.0], [True, 0], [0.0], "0,0", None, [5e8, -5e8])
        )


JSON_MUTATORS: dict[str, Mutator] = {
    "json_leaf": json_edit(_leaf_value),
    "json_drop_key": json_edit(_drop_key),
    "json_add_key": json_edit(_add_key),
}
LINE_MAP_MUTATORS: dict[str, Mutator] = {
    "map_line_field": json_edit(_line_field),
    "map_move_end": json_edit(_move_end),
    "map_covariance": json_edit(_covariance),
    "map_origin": json_edit(_origin),
}
