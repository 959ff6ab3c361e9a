"""A method's settings are named only in its module and its kernel's binding.

Every built-in method declares its settings once, grouped by purpose, in its module
(shared groups once in the step that uses them); the rest of the package passes them
through without naming a field. The checks read the source: in Python, string constants
(docstrings aside) and keyword arguments; in C++, string literals.
"""

from __future__ import annotations

import ast
import inspect
import re
from collections import defaultdict
from pathlib import Path

import pytest

import scanlines
from scanlines import Extractor
from scanlines.methods import REGISTRY, CompiledMethod, Method
from scanlines.steps import assemble, breakpoints, events

PACKAGE = Path(scanlines.__file__).parent
BINDINGS = PACKAGE.parents[1] / "cpp" / "bindings"
KERNELS = PACKAGE.parents[1] / "cpp" / "scanlines"

#: The modules that pass settings through: they may name no setting.
PASS_THROUGH = (
    "cli",
    "runs",
    "sensor",
    "params",
    "config.py",
    "extractor.py",
    "builtin_methods.py",
    "methods/base.py",
    "methods/__init__.py",
    "ros2/parameters.py",
)

#: Words of these modules that are a method setting's name but mean something else here.
HOMONYMS = {
    "cli/bench.py": {"seed"},  # the benchmark's scene seed
}

#: The shared groups, declared once, in the step that uses them.
SHARED = {
    "steps/breakpoints.py": set(breakpoints.CLUSTERING),
    "steps/events.py": set(events.EVENTS),
    "steps/assemble.py": set(assemble.output_settings(2)),
}
SHARED_READER = "arrays.hpp"  # the bindings' one reader of each shared group
READ = re.compile(r'\(\s*\w+\s*,\s*"(\w+)"\s*\)')
"""A C++ read by name: ``setting<T>(record, "name")``, ``group(record, "name")``."""


def builtin_methods() -> dict[str, type[Method]]:
    return dict(REGISTRY)


def setting_names(method: type[Method]) -> set[str]:
    """The method's parameters and the fields of its kernel's record."""
    names = set(method.parameters)
    if issubclass(method, CompiledMethod) and method.settings is not None:
        record = method.record_of(Extractor(method.name).params)
        names |= {field for group in record.values() for field in group}
    return names


def owners() -> dict[str, set[str]]:
    """Setting name -> the modules (relative to the package) that may name it: the modules
    of each method having it (its class and the classes it builds on, but the protocol)."""
    out: dict[str, set[str]] = defaultdict(set)
    for method in builtin_methods().values():
        modules = {
            relative(inspect.getsourcefile(cls))
            for cls in method.__mro__
            if cls.__module__.startswith("scanlines.methods.")
            and cls.__module__ != "scanlines.methods.base"
        }
        for name in setting_names(method):
            out[name] |= modules
    for module, names in SHARED.items():
        for name in names:
            out[name].add(module)
    return out


def relative(path: str | Path) -> str:
    return Path(path).resolve().relative_to(PACKAGE).as_posix()


def named_in_python(path: Path, names: set[str], keywords: bool = True) -> set[tuple[str, int]]:
    """``(name, line)`` of each of ``names`` that ``path`` declares or reads: a key of a dict
    display, a subscript, the first argument of ``get``, ``pop``, ``setdefault`` or
    ``getattr``, and (with ``keywords``) a keyword argument."""
    tree = ast.parse(path.read_text())
    keys = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            keys += node.keys
        elif isinstance(node, ast.Subscript):
            keys.append(node.slice)
        elif isinstance(node, ast.Call) and node.args:
            function = node.func
            called = function.attr if isinstance(function, ast.Attribute) else None
            if isinstance(function, ast.Name) and function.id == "getattr":
                keys.append(node.args[1] if len(node.args) > 1 else None)
            elif called in ("get", "pop", "setdefault"):
                keys.append(node.args[0])
    found = {
        (key.value, key.lineno)
        for key in keys
        if isinstance(key, ast.Constant) and key.value in names
    }
    if keywords:
        found |= {
            (node.arg, node.value.lineno)
            for node in ast.walk(tree)
            if isinstance(node, ast.keyword) and node.arg in names
        }
    return found


def python_modules(*parts: str) -> list[Path]:
    out = []
    for part in parts:
        path = PACKAGE / part
        out += sorted(path.rglob("*.py")) if path.is_dir() else [path]
    return out


ALL_NAMES = set(owners())


def test_the_methods_and_their_groups_are_found():
    found = owners()
    assert "scanlines/methods/adaptive.py" not in found  # paths are package-relative
    assert found["merge_chi2"] >= {"methods/adaptive.py", "methods/split_merge.py"}
    assert found["estimate_noise"] == {"methods/adaptive.py"}  # a kernel field
    assert "methods/consensus.py" in found["inlier_distance"]  # RANSAC and Hough's loop
    assert found["min_points"] >= {"steps/assemble.py", "methods/partition.py"}
    assert "methods/base.py" not in set().union(*found.values())


@pytest.mark.parametrize("module", python_modules(*PASS_THROUGH), ids=relative)
def test_the_modules_that_pass_settings_through_name_none(module):
    allowed = HOMONYMS.get(relative(module), set())
    named = {
        (name, line) for name, line in named_in_python(module, ALL_NAMES) if name not in allowed
    }
    assert not named, f"{relative(module)} names settings: {sorted(named)}"


@pytest.mark.parametrize("module", python_modules("methods", "steps"), ids=relative)
def test_a_method_module_names_only_its_own_settings(module):
    found = owners()
    stray = {
        (name, line)
        for name, line in named_in_python(module, ALL_NAMES, keywords=False)
        if relative(module) not in found[name]
    }
    assert not stray, f"{relative(module)} names settings of other methods: {sorted(stray)}"


def binding_of(method: type[Method]) -> str:
    """The binding file that defines the method's stack kernel."""
    kernel = method.kernel.__code__.co_names[-1]
    files = [p.name for p in BINDINGS.glob("*.cpp") if f'"{kernel}"' in p.read_text()]
    assert len(files) == 1, (method.name, kernel, files)
    return files[0]


def test_each_binding_reads_only_its_methods_settings():
    compiled = [m for m in builtin_methods().values() if issubclass(m, CompiledMethod)]
    readers: dict[str, set[str]] = defaultdict(set)
    for method in compiled:
        for name in setting_names(method):
            readers[name].add(binding_of(method))
    for names in SHARED.values():
        for name in names:
            readers[name].add(SHARED_READER)
    stray = []
    for path in sorted([*BINDINGS.glob("*.cpp"), *BINDINGS.glob("*.hpp")]):
        for line_number, line in enumerate(path.read_text().splitlines(), 1):
            for name in READ.findall(line):
                if name in readers and path.name not in readers[name]:
                    stray.append((path.name, line_number, name))
    assert not stray, f"settings read outside their method's binding: {stray}"
    assert binding_of(REGISTRY["pdbs"]) == binding_of(REGISTRY["iepf"])


def test_the_kernels_take_typed_settings_never_names():
    named = [
        (path.relative_to(KERNELS).as_posix(), name)
        for path in sorted(KERNELS.rglob("*.[ch]pp"))
        for name in READ.findall(path.read_text())
        if name in ALL_NAMES
    ]
    assert not named, named


def test_the_check_finds_a_setting_named_where_it_does_not_belong(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text(
        '"""penalty in a docstring is fine."""\nvalue = params["penalty"]\nf(k=3)\n'
        'word = "fit"\nspec = {"window": 1}\nsettings.get("seed")\n'
    )
    found = {("penalty", 2), ("k", 3), ("window", 5), ("seed", 6)}
    assert named_in_python(planted, ALL_NAMES) == found
    assert READ.findall('s.penalty = setting<double>(segments, "penalty");') == ["penalty"]
