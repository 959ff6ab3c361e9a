"""A simple reader of the C++ sources in cpp/: function definitions, their bodies and calls."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

CPP = Path(__file__).parents[1] / "cpp"

KEYWORDS = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof"}
NAME = re.compile(r"[A-Za-z_]\w*")
OPENING = {"(": ")", "[": "]", "{": "}"}


@dataclass(frozen=True)
class Function:
    """One function defined in a source file: where, its parameters' names and its body."""

    name: str
    path: Path
    first_line: int
    last_line: int
    parameters: tuple[str, ...]
    body: str

    @property
    def lines(self) -> int:
        return self.last_line - self.first_line + 1


def blanked(text: str) -> str:
    """The text with comments, string and character literals blanked (newlines kept)."""
    pattern = re.compile(
        r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'|^[ \t]*#[^\n]*'
        r"|\b(?:public|private|protected)[ \t]*:(?!:)",
        re.S | re.M,
    )
    return pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def closing(text: str, at: int) -> int:
    """The index of the bracket that closes the one at ``at``."""
    want, depth = [], 0
    for i in range(at, len(text)):
        c = text[i]
        if c in OPENING:
            want.append(OPENING[c])
            depth += 1
        elif want and c == want[-1]:
            want.pop()
            if not want:
                return i
    raise ValueError(f"unbalanced bracket at {at}")


def split_top(text: str) -> list[str]:
    """``text`` split at the commas outside brackets (angle brackets of templates included)."""
    parts, depth, start = [], 0, 0
    for i, c in enumerate(text):
        if c in "([{<":
            depth += 1
        elif c in ")]}>":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts if p.strip()]


def _parameter_name(parameter: str) -> str:
    names = NAME.findall(parameter.split("=")[0])
    return names[-1] if names else ""


def _function_head(head: str) -> tuple[str, str] | None:
    """(name, parameter text) when the text before a ``{`` heads a function definition."""
    head = head.strip()
    declared_type = r"(template\s*<.*>\s*)?(struct|class|union|enum|namespace)\b"
    if not head or re.match(declared_type, head, re.S):
        return None
    for m in re.finditer(r"(~?[A-Za-z_]\w*|operator\s*\S+?)\s*\(", head):
        if m.group(1) in KEYWORDS or "=" in head[: m.start()]:
            return None
        end = closing(head, m.end() - 1)
        rest = head[end + 1 :].strip()
        # After the parameters: qualifiers, a trailing return type or a constructor's
        # member initialisers, nothing else.
        if re.fullmatch(r"((const|noexcept|override|final|mutable)\s*)*(->.*|:.*)?", rest, re.S):
            return m.group(1), head[m.end() : end]
        return None
    return None


def functions(path: Path) -> list[Function]:
    """Every function defined in one source file, members and nested classes' included."""
    text = blanked(path.read_text())
    found: list[Function] = []
    scopes = [0]  # start of the current statement at each enclosing namespace or class level
    i = 0
    while i < len(text):
        c = text[i]
        if c in ";":
            scopes[-1] = i + 1
        elif c == "{":
            head = text[scopes[-1] : i]
            fn = _function_head(head)
            if fn is not None:
                end = closing(text, i)
                first = scopes[-1] + len(head) - len(head.lstrip())
                found.append(
                    Function(
                        fn[0],
                        path,
                        text.count("\n", 0, first) + 1,
                        text.count("\n", 0, end) + 1,
                        tuple(_parameter_name(p) for p in split_top(fn[1])),
                        text[i + 1 : end],
                    )
                )
                i = end
                scopes[-1] = end + 1
            elif re.search(r"\b(struct|class|union|namespace)\b[^=()]*$", head.strip(), re.S):
                scopes.append(i + 1)
            else:  # an initialiser or an enum: skipped whole
                i = closing(text, i)
        elif c == "}":
            scopes.pop()
            if not scopes:
                raise ValueError(f"{path}: unbalanced braces")
            scopes[-1] = i + 1
        i += 1
    return found


def all_functions(*folders: str) -> list[Function]:
    """The functions of every .cpp and .hpp file under the given folders of cpp/."""
    out: list[Function] = []
    for folder in folders:
        for path in sorted((CPP / folder).rglob("*.[ch]pp")):
            out.extend(functions(path))
    return out


def calls(body: str) -> list[tuple[str, list[str]]]:
    """The free-function calls in a body: (name, argument texts), member calls left out."""
    out = []
    for m in re.finditer(r"(?<![\w.>:])([A-Za-z_]\w*)\s*(<[^;(){}]*?>)?\s*\(", body):
        if m.group(1) in KEYWORDS:
            continue
        end = closing(body, m.end() - 1)
        out.append((m.group(1), split_top(body[m.end() : end])))
    return out


def _carries(argument: str, names: set[str]) -> bool:
    return any(re.search(rf"(?<![\w.>]){re.escape(name)}\b", argument) for name in names)


def _aliases(body: str, names: set[str]) -> set[str]:
    """``names`` and the local names bound to one of them or a member of one
    (``const RuleSpec& rule = s.rule;``), until no new name is found."""
    names = set(names)
    while True:
        found = {
            m.group(1)
            for m in re.finditer(r"([A-Za-z_]\w*)\s*=\s*([A-Za-z_][\w.]*)\s*;", body)
            if m.group(2).split(".")[0] in names
        }
        if found <= names:
            return names
        names |= found


def settings_walk(defined: list[Function], root: str, parameter: str) -> list[tuple[str, str]]:
    """The calls that pass a settings record (or a part of it: a group, a field, a local
    name bound to one) on from ``root``'s ``parameter``, followed into every function defined
    in ``defined`` that receives it: (caller, callee) per call site, each function's body
    walked once per set of receiving parameters."""
    by_name: dict[str, list[Function]] = {}
    for function in defined:
        by_name.setdefault(function.name, []).append(function)
    stops: list[tuple[str, str]] = []
    seen: set[tuple[str, Path, int, frozenset[str]]] = set()
    todo = [(function, {parameter}) for function in by_name[root]]
    while todo:
        function, names = todo.pop()
        key = (function.name, function.path, function.first_line, frozenset(names))
        if key in seen:
            continue
        seen.add(key)
        names = _aliases(function.body, names)
        for callee, arguments in calls(function.body):
            carried = [i for i, argument in enumerate(arguments) if _carries(argument, names)]
            if not carried or callee not in by_name:
                continue
            stops.append((function.name, callee))
            for target in by_name[callee]:
                if len(target.parameters) >= len(arguments):
                    todo.append((target, {target.parameters[i] for i in carried}))
    return stops
