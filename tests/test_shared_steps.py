"""``cpp/scanlines/steps/`` holds only shared steps: no step is used by one method alone.

Every function declared in ``cpp/scanlines/steps/*.hpp`` must be reached by at least two
methods. The functions are read from the headers; who calls whom is read from the
kernels' sources:

- a method is a root of the compiled call graph (a function of
  ``cpp/scanlines/methods/*.cpp`` that no other kernel function calls: a stack kernel such
  as ``iepf_stack``, or ``cluster_scan``, the clustering of every Python method), or a
  Python module of ``src/scanlines/methods/`` or ``src/scanlines/steps/`` that calls the
  step through :mod:`scanlines._core` or imports its wrapper (a steps module's wrapper of
  its own kernel does not count: it documents the step, it does not use it);
- a step reaches what it calls, so a helper of a shared step (``criterion_value`` inside
  ``best_level``) or a step another step calls (``neighbour_steps`` in ``turn_window``)
  is shared with it.

A function only one method reaches belongs in that method's files
(``cpp/scanlines/methods/<method>.cpp``, its module in ``src/scanlines/methods/``).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

REPOSITORY = Path(__file__).parents[1]
STEPS = REPOSITORY / "cpp" / "scanlines" / "steps"
METHODS = REPOSITORY / "cpp" / "scanlines" / "methods"
PYTHON = REPOSITORY / "src" / "scanlines"

# A declaration or definition at namespace scope: these sources never indent it, while
# struct and class members (Moments' accessors, Table::add) are indented and are not steps,
# so the pattern starts at the line's first column and does not cross lines before the name.
DECLARATION = re.compile(
    r"^(?!(?:struct|class|enum|using|namespace|return|typedef|template)\b)"
    r"(?:inline[ \t]+|static[ \t]+|constexpr[ \t]+)*[A-Za-z_][\w:<>,\*& \t]*?[\s\*&]"
    r"([A-Za-z_]\w*)[ \t]*\(",
    re.M,
)


def _declared(header: Path) -> list[str]:
    """The functions a header declares (or defines inline) at namespace scope."""
    text = re.sub(r"//[^\n]*", "", header.read_text())
    return sorted({m.group(1) for m in DECLARATION.finditer(text)})


def _definitions(source: Path) -> dict[str, str]:
    """The bodies of the functions a source file defines at namespace scope, by name."""
    text = re.sub(r"//[^\n]*", "", source.read_text())
    out: dict[str, str] = {}
    for m in DECLARATION.finditer(text):
        # The parameter list, then ``{`` (a definition) or ``;`` (a declaration).
        depth, i = 0, m.end() - 1
        while True:
            depth += {"(": 1, ")": -1}.get(text[i], 0)
            i += 1
            if depth == 0:
                break
        rest = text[i:].lstrip()
        if rest.startswith("const"):
            rest = rest[len("const") :].lstrip()
        if not rest.startswith("{"):
            continue
        start = text.index("{", i)
        depth, j = 0, start
        while True:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
            if depth == 0:
                break
        out[m.group(1)] = out.get(m.group(1), "") + text[start:j]
    return out


def _calls(body: str, name: str) -> bool:
    """Whether ``body`` calls ``name``, or passes it as an argument (``each_row(stack, f)``)."""
    called = rf"(?<![\w.>]){re.escape(name)}\s*\("
    passed = rf"[(,]\s*{re.escape(name)}\s*[,)]"
    return re.search(f"{called}|{passed}", body) is not None


def _python_users(name: str, twin: str) -> set[str]:
    """The Python methods and steps modules that use step ``name`` (its twin: the steps
    module that documents it and wraps its binding)."""
    users = set()
    for module in sorted([*(PYTHON / "methods").glob("*.py"), *(PYTHON / "steps").glob("*.py")]):
        if module.parent.name == "steps" and module.stem == twin:
            continue
        tree = ast.parse(module.read_text())
        for node in ast.walk(tree):
            core = (
                isinstance(node, ast.Attribute)
                and node.attr == name
                and isinstance(node.value, ast.Name)
                and node.value.id == "_core"
            )
            imported = (
                isinstance(node, ast.ImportFrom)
                and (node.module or "").startswith("scanlines.steps")
                and any(alias.name == name for alias in node.names)
            )
            if core or imported:
                users.add(f"{module.parent.name}/{module.name}")
                break
    return users


def _methods_reaching() -> dict[str, set[str]]:
    """Each function of the steps' headers -> the methods that reach it."""
    steps = {name: header.stem for header in STEPS.glob("*.hpp") for name in _declared(header)}
    bodies: dict[str, str] = {}  # every kernel function, steps and methods, by name
    method_functions: dict[str, str] = {}  # a method kernel's function -> its file
    for source in sorted([*STEPS.glob("*.cpp"), *STEPS.glob("*.hpp"), *METHODS.glob("*.cpp")]):
        for name, body in _definitions(source).items():
            bodies[name] = bodies.get(name, "") + body
            if source.parent == METHODS:
                method_functions[name] = source.name
    called = {
        callee
        for caller, body in bodies.items()
        for callee in bodies
        if callee != caller and _calls(body, callee)
    }
    roots = [name for name in method_functions if name not in called]
    reach: dict[str, set[str]] = {name: set() for name in steps}
    for root in roots:
        seen, todo = {root}, [root]
        while todo:
            body = bodies[todo.pop()]
            for callee in bodies:
                if callee not in seen and _calls(body, callee):
                    seen.add(callee)
                    todo.append(callee)
        for name in seen & steps.keys():
            reach[name].add(f"{method_functions[root]}:{root}")
    for name, twin in steps.items():
        reach[name] |= _python_users(name, twin)
    return reach


def test_the_headers_are_read():
    reach = _methods_reaching()
    # The parse finds the steps every method uses, and each reached by its users.
    for name in ("prefix_moments", "valid_returns", "assemble", "run_cost", "median"):
        assert name in reach
    assert len(reach) > 60
    assert "paper.cpp:paper_stack" in reach["sweep_levels"]
    assert "adaptive.cpp:adaptive_stack" in reach["sweep_levels"]


def test_every_step_is_shared():
    single = {name: sorted(users) for name, users in _methods_reaching().items() if len(users) < 2}
    assert not single, f"steps used by one method only (move them to it): {single}"
