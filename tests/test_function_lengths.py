"""No function of the package or of its compiled core is longer than 80 lines.

Python functions are read with :mod:`ast` (from the ``def`` line to the last line of the
body, docstring included), C++ functions with the brace-matching reader of
``tests/cpp_sources.py`` (from the first line of the declaration to the closing brace).
The command line (``src/scanlines/cli/``) is left out: its commands are long lists of
options.
"""

from __future__ import annotations

import ast
from pathlib import Path

import cpp_sources

REPOSITORY = Path(__file__).parents[1]
PACKAGE = REPOSITORY / "src" / "scanlines"
LONGEST = 80

# Longer functions allowed, by (file relative to the repository, function): each with its
# reason.
ALLOWED = {
    # The paper method as printed: one comment per step with its equation, kept whole.
    ("cpp/scanlines/methods/paper.cpp", "paper_scan"),
}


def _python_lengths() -> list[tuple[str, str, int]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(REPOSITORY).as_posix()
        if relative.startswith("src/scanlines/cli/"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out.append((relative, node.name, node.end_lineno - node.lineno + 1))
    return out


def _cpp_lengths() -> list[tuple[str, str, int]]:
    return [
        (f.path.relative_to(REPOSITORY).as_posix(), f.name, f.lines)
        for f in cpp_sources.all_functions("scanlines", "bindings")
    ]


def test_no_function_is_longer_than_80_lines():
    lengths = _python_lengths() + _cpp_lengths()
    too_long = [
        f"{path}: {name} ({lines} lines)"
        for path, name, lines in lengths
        if lines > LONGEST and (path, name) not in ALLOWED
    ]
    assert not too_long, "longer than 80 lines:\n" + "\n".join(too_long)


def test_the_allowed_functions_exist():
    found = {(path, name) for path, name, _ in _python_lengths() + _cpp_lengths()}
    assert found >= ALLOWED, sorted(ALLOWED - found)


def test_the_readers_measure_known_functions():
    cpp = {(path, name): lines for path, name, lines in _cpp_lengths()}
    python = {(path, name): lines for path, name, lines in _python_lengths()}
    # Lengths a reader that lost its place would get wrong: a one-line inline function in
    # a header and a long kernel.
    assert cpp[("cpp/scanlines/core.hpp", "py_mod")] <= 10
    assert cpp[("cpp/scanlines/methods/paper.cpp", "paper_scan")] > 60
    assert python[("src/scanlines/methods/adaptive.py", "kernel_arguments")] > 3
    assert len(cpp) > 200
