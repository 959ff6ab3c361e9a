"""The public API: names, registry, parameter validation, result types."""

from __future__ import annotations

import ast
import importlib
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import scanlines
from scanlines import Extraction, Extractor, ParameterError, extract
from scenes import scan_of, square_room


def test_public_names():
    for name in ("Scan", "Extractor", "extract", "Extraction", "Segment", "ScanError", "methods"):
        assert hasattr(scanlines, name)
    assert "adaptive" in scanlines.method_names()
    assert all(isinstance(name, str) for name in scanlines.method_names())


def test_import_loads_no_cli_plot_or_bag_dependency():
    code = (
        "import sys, scanlines; "
        "heavy = ('matplotlib', 'typer', 'rich', 'rosbags'); "
        "heavy = [m for m in heavy if m in sys.modules]; "
        "print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_the_first_result_of_every_method_comes_at_once_in_a_fresh_process():
    """Nothing compiles at run time: the kernels were compiled at install. Measured in
    processor time of the fresh process, which a busy machine does not stretch as it
    stretches wall time (a compiler at first call took tens of seconds of it)."""
    code = (
        "import time; started = time.process_time(); "
        "import numpy as np, scanlines; "
        "r = 2.0 / np.maximum(np.abs(np.cos(np.linspace(-1, 1, 361))), 0.3); "
        "scan = scanlines.Scan(r, -1.0, 2.0 / 360); "
        "found = [len(scanlines.extract(scan, method=m)) for m in scanlines.method_names()]; "
        "print(min(found), time.process_time() - started)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    fewest, seconds = out.stdout.split()
    assert int(fewest) >= 1
    assert float(seconds) < 5.0  # 0.2-0.3 s here


def test_unknown_method_lists_the_valid_ones():
    with pytest.raises(ParameterError, match="adaptive"):
        Extractor(method="nope")


def test_unknown_preset_lists_the_valid_ones():
    with pytest.raises(ParameterError, match="paper"):
        Extractor(preset="fast")


def test_unknown_parameter_lists_the_valid_ones():
    with pytest.raises(ParameterError, match="window") as info:
        Extractor(windw=5)
    assert "windw" in str(info.value)


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("k", -1.0),
        ("k", "abc"),
        ("window", 0),
        ("window", 2.5),
        ("fit", "ols"),
        ("dkth_range", (0.5, 0.1)),
    ],
)
def test_bad_parameter_values_are_refused(name, value):
    with pytest.raises(ParameterError, match=name):
        Extractor(**{name: value})


def test_parameters_from_strings_as_the_cli_passes_them():
    extractor = Extractor(
        k="2.5", window="8", merge="false", dkth_range="0,0.1", max_residual="none"
    )
    assert extractor.params["k"] == 2.5
    assert extractor.params["window"] == 8
    assert extractor.params["merge"] is False
    assert extractor.params["dkth_range"] == (0.0, 0.1)
    assert extractor.params["max_residual"] is None


def test_extraction_is_cheap_arrays_with_segment_views():
    scan = scan_of(square_room(), fov_deg=340, step_deg=1 / 3, sigma=0.01, seed=0, start_deg=-170)
    result = extract(scan)
    assert isinstance(result, Extraction)
    assert result.lines.shape == (5, 7)
    segment = result.segments[1]
    assert segment.first == result.first[1]
    assert segment.length == pytest.approx(np.hypot(*(np.subtract(segment.end, segment.start))))
    assert segment.covariance.shape == (2, 2)
    assert result.breakpoints.dtype.kind == "i"
    data = json.loads(json.dumps(result.to_dict()))
    assert len(data["segments"]) == 5
    assert data["params"]["fit"] == "tls"
    with pytest.raises(ValueError, match="read-only"):
        result.first[0] = 3


@pytest.mark.parametrize("method", scanlines.method_names())
def test_method_info_documents_every_parameter(method):
    info = scanlines.method_info(method)
    assert set(info["params"]) == set(Extractor(method).params)
    assert all(param.doc and param.allowed for param in info["params"].values())
    assert info["doc"]


def test_paper_preset_exists():
    assert "paper" in scanlines.method_info("adaptive")["presets"]


def _module_imports(path: Path, package: str, modules: set[str]) -> set[str]:
    """The package's modules a module imports, at its top level or inside a function:
    ``from a.b import c`` imports ``a.b.c`` if that is a module, else ``a.b``."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            for alias in node.names:
                submodule = f"{base}.{alias.name}"
                found.add(submodule if submodule in modules else base)
    return found & modules


def import_graph(root: Path) -> dict[str, list[str]]:
    """Module -> the package's modules it imports (function-level imports counted)."""
    modules = {}
    for path in root.rglob("*.py"):
        parts = path.relative_to(root.parent).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        name = ".".join(parts[:-1] if is_package else parts)
        modules[name] = (path, name if is_package else name.rpartition(".")[0])
    names = modules.keys() | COMPILED_MODULES
    graph = {
        name: sorted(_module_imports(path, package, names) - {name})
        for name, (path, package) in modules.items()
    }
    return graph | {name: [] for name in COMPILED_MODULES if root.name == "scanlines"}


COMPILED_MODULES = {"scanlines._core"}
"""The package's compiled modules (C++: they import none of its Python modules)."""


def import_cycles(graph: dict[str, list[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles = []

    def connect(name: str) -> None:
        index[name] = low[name] = len(index)
        stack.append(name)
        for imported in graph[name]:
            if imported not in index:
                connect(imported)
                low[name] = min(low[name], low[imported])
            elif imported in stack:
                low[name] = min(low[name], index[imported])
        if low[name] == index[name]:
            group = []
            while not group or group[-1] != name:
                group.append(stack.pop())
            if len(group) > 1:
                cycles.append(sorted(group))

    for name in graph:
        if name not in index:
            connect(name)
    return cycles


#: The package's areas from the bottom up: a module may import its own area and those
#: below it, never one above (the first prefix that matches names a module's area). The
#: layout table of docs/ARCHITECTURE.md gives each module and subpackage its layer here.
LAYERS = (
    ("scanlines._core", "scanlines.errors", "scanlines.outputs", "scanlines.params",
     "scanlines.truth", "scanlines.builtin_methods", "scanlines.reader_options",
     "scanlines.report", "scanlines.untrusted"),
    ("scanlines.scan", "scanlines.extraction"),
    ("scanlines.geometry",),
    ("scanlines.steps",),
    ("scanlines.methods",),
    ("scanlines.extractor", "scanlines.sensor", "scanlines.config", "scanlines.sim"),
    ("scanlines.io", "scanlines.data"),
    ("scanlines.runs", "scanlines.ros2", "scanlines.map"),
    ("scanlines.bench",),
    ("scanlines.evaluation",),
    ("scanlines.viz", "scanlines.viewer"),
    ("scanlines.cli", "scanlines.__main__"),
)  # fmt: skip


def layer_of(name: str) -> int:
    for level, prefixes in enumerate(LAYERS):
        if any(name == prefix or name.startswith(prefix + ".") for prefix in prefixes):
            return level
    return -1  # the package itself, and anything not placed: fails the test below


def upward_imports(graph: dict[str, list[str]]) -> list[str]:
    return [
        f"{name} -> {imported}"
        for name, imports in graph.items()
        if name != "scanlines"
        for imported in imports
        if imported != "scanlines" and layer_of(imported) > layer_of(name)
    ]


def test_modules_import_without_cycles_or_upward_arrows():
    """The package's import graph, counting imports inside functions, has no circle, and
    no module imports an area above its own (``LAYERS``)."""
    graph = import_graph(Path(scanlines.__file__).parent)
    assert len(graph) > 50
    assert import_cycles(graph) == []
    unplaced = [name for name in graph if name != "scanlines" and layer_of(name) < 0]
    assert unplaced == []
    assert upward_imports(graph) == []
    for name in ("scanlines.steps.select", "scanlines.methods.adaptive", "scanlines.evaluation"):
        importlib.import_module(name)


REPOSITORY = Path(__file__).parents[1]
SOURCE = REPOSITORY / "src" / "scanlines"
ARCHITECTURE = REPOSITORY / "docs" / "ARCHITECTURE.md"


def test_the_top_level_holds_the_core_types_and_entry_points_only():
    """At most 12 modules beside ``__init__.py`` and ``__main__.py``; the rest live in
    subpackages by purpose."""
    modules = sorted(p.name for p in SOURCE.glob("*.py"))
    assert len(set(modules) - {"__init__.py", "__main__.py"}) <= 12, modules


def test_no_module_is_over_500_lines():
    lines = {p.relative_to(SOURCE): len(p.read_text().splitlines()) for p in SOURCE.rglob("*.py")}
    assert {str(name): n for name, n in lines.items() if n > 500} == {}


def _section(title: str) -> str:
    text = ARCHITECTURE.read_text()
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end > 0 else len(text)]


def layout_table() -> dict[str, tuple[str, str]]:
    """The package table of docs/ARCHITECTURE.md's "Layout": name -> (layer, what)."""
    rows = re.findall(r"^\| (\d+|-) \| `([^`]+)` \| (.+) \|$", _section("Layout"), flags=re.M)
    names = [name for _, name, _ in rows]
    assert len(names) == len(set(names)), names
    return {name: (layer, what) for layer, name, what in rows}


def test_the_layout_table_names_every_module_and_subpackage_and_nothing_gone():
    table = layout_table()
    tree = {p.name for p in SOURCE.glob("*.py")} | {
        f"{p.name}/" for p in SOURCE.iterdir() if (p / "__init__.py").is_file()
    }
    assert sorted(tree - table.keys()) == [], "in the tree, not in the table"
    assert sorted(table.keys() - tree) == [], "in the table, gone from the tree"
    for name, (layer, what) in table.items():
        module = "scanlines." + name.removesuffix(".py").removesuffix("/")
        expected = "-" if name == "__init__.py" else str(layer_of(module))
        assert layer == expected, f"{name}: layer {layer} in the table, {expected} in LAYERS"
        for inner in re.findall(r"`([\w/]+\.py)`", what):
            path = SOURCE / inner if "/" in inner else SOURCE / name / inner
            assert path.is_file(), f"{name}: {inner} is gone"


def _named_path(token: str) -> bool:
    """Whether a path the page names exists, from the repository, the package or docs/
    (``map/fusion.LineMap``: the module ``map/fusion.py``)."""
    head, _, name = token.rstrip("/").rpartition("/")
    module = f"{head}/{name.split('.')[0]}.py"
    bases = (REPOSITORY, SOURCE, REPOSITORY / "docs")
    return any((base / token).exists() or (base / module).is_file() for base in bases)


def test_every_path_the_architecture_page_names_exists():
    """Paths in backquotes that start at a folder of the repository or of the package
    (``io/writers.py``, ``cpp/bindings/``, ``map/fusion.LineMap``), and the subpackages
    of the data-flow picture."""
    text = ARCHITECTURE.read_text()
    folders = {p.name for p in (*REPOSITORY.iterdir(), *SOURCE.iterdir()) if p.is_dir()}
    paths = {
        token
        for token in re.findall(r"`([\w.-]+(?:/[\w.-]+)+/?)`", text)
        if token.split("/")[0] in folders
    }
    assert len(paths) > 50
    assert sorted(token for token in paths if not _named_path(token)) == []
    (picture,) = re.findall(r"```mermaid\n(.*?)```", text, flags=re.DOTALL)
    folders = set(re.findall(r"\b([a-z0-9_]+)/", picture.replace("<br/>", " ")))
    assert folders >= {"io", "steps", "methods", "runs", "map", "ros2", "bench", "evaluation"}
    assert sorted(f for f in folders if not (SOURCE / f).is_dir() and f != "cpp") == []


def test_the_cycle_check_finds_a_planted_circle_and_an_upward_arrow(tmp_path):
    package = tmp_path / "scanlines"
    (package / "io").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "errors.py").write_text("def f():\n    from scanlines.io.reader import R\n")
    (package / "io" / "__init__.py").write_text("")
    (package / "io" / "reader.py").write_text("from ..errors import f\nR = 1\n")
    graph = import_graph(package)
    assert graph["scanlines.io.reader"] == ["scanlines.errors"]
    assert import_cycles(graph) == [["scanlines.errors", "scanlines.io.reader"]]
    assert upward_imports(graph) == ["scanlines.errors -> scanlines.io.reader"]


def test_plot_title_counts_features_in_words():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    from scanlines.viz.scans import plot_extraction

    scan = scan_of([((2.0, -3.0), (2.0, 3.0))], fov_deg=90, step_deg=1.0)  # one wall
    title = plot_extraction(scan, extract(scan), title="wall").get_title()
    assert title == "wall\n1 segment, 0 breakpoints, 0 corners"


def test_an_extractor_pickles_with_its_parameters():
    import pickle

    extractor = scanlines.Extractor("iepf", split_distance=0.05)
    copy = pickle.loads(pickle.dumps(extractor))
    assert (copy.method, copy.preset, dict(copy.params)) == (
        "iepf",
        None,
        dict(extractor.params),
    )
    scan = scan_of([((2.0, -3.0), (2.0, 3.0))], fov_deg=90, step_deg=1.0)
    assert copy(scan).first.tolist() == extractor(scan).first.tolist()


def test_the_core_readme_is_true_to_the_tree():
    """``cpp/README.md``'s listing: every folder of the core has its line, and every file it
    names (``filter.cpp``, ``scanlines/core.hpp``) is in the core."""
    core = REPOSITORY / "cpp"
    text = (core / "README.md").read_text()
    (listing,) = re.findall(r"```\n(CMakeLists.txt.*?)```", text, flags=re.DOTALL)
    described = set(re.findall(r"^([\w/]+/)\s", listing, flags=re.MULTILINE))
    folders = {f"{p.relative_to(core).as_posix()}/" for p in core.rglob("*") if p.is_dir()}
    folders = {f for f in folders if f.count("/") <= 2 and f != "scanlines/"}
    assert folders <= described, sorted(folders - described)
    files = {p.name for p in core.rglob("*") if p.is_file()}
    named = re.findall(r"\b([\w/]+\.(?:cpp|hpp))\b", text)
    assert sorted(n for n in named if n.rsplit("/", 1)[-1] not in files) == []
