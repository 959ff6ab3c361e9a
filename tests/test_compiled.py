"""The kernels are one implementation: compiled and plain-Python runs agree exactly.

``NUMBA_DISABLE_JIT=1`` runs every kernel as ordinary Python, which is also what
the package does when numba is not installed.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from scanlines import Extractor, _jit
from scanlines.builtin_methods import BUILTIN_METHODS
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.methods import CompiledMethod, method_class

SCRIPT = """
import json, sys
from scanlines import Extractor
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.methods import CompiledMethod, method_class
method = sys.argv[1]
scans = list(open_log(sample("intel")))[:3]
out = []
for preset in (None, "paper") if method == "adaptive" else (None,):
    for scan in scans:
        e = Extractor(method, preset=preset)(scan)
        out.append([e.first.tolist(), e.last.tolist(), e.breakpoints.tolist(),
                    e.corners.tolist(), e.outliers.tolist(), e.lines.tolist()])
json.dump(out, sys.stdout)
"""


COMPILED_METHODS = ("adaptive", "iepf", "pdbs", "split_merge")
ALL_METHODS = BUILTIN_METHODS


def _run(disable_jit: bool, method: str = "adaptive") -> list:
    env = dict(os.environ, NUMBA_DISABLE_JIT="1" if disable_jit else "0")
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, method], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


@pytest.mark.parametrize("method", COMPILED_METHODS)
def test_plain_python_kernels_give_the_compiled_results(method):
    compiled, plain = _run(False, method), _run(True, method)
    assert len(compiled) == len(plain) == (6 if method == "adaptive" else 3)
    for fast, slow in zip(compiled, plain, strict=True):
        assert fast[:5] == slow[:5]  # beam indices identical
        np.testing.assert_allclose(
            np.array(fast[5], dtype=float),
            np.array(slow[5], dtype=float),
            atol=1e-9,
            equal_nan=True,
        )


def test_each_module_caches_under_the_hash_of_what_it_imports(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    directory = _jit.cache_dir("scanlines.methods.iepf")
    assert directory.parent == tmp_path
    assert directory.name == f"methods.iepf-{_jit._source_hash('scanlines.methods.iepf')}"
    files = {path.name for path in _jit._imported_files("scanlines.methods.iepf")}
    assert {"iepf.py", "base.py", "split.py", "fit.py", "_jit.py", "scan.py"} <= files
    assert not {"hough.py", "adaptive.py", "partition.py"} & files


def test_an_edit_to_one_method_leaves_the_other_methods_cached(monkeypatch, tmp_path):
    """A copy of the package with ``hough.py`` edited: hough's key changes, every
    method's key that does not import it stays; an edit to a step changes them all."""
    copy = tmp_path / "scanlines"
    shutil.copytree(Path(_jit.__file__).parent, copy, ignore=shutil.ignore_patterns("*.pyc"))
    monkeypatch.setattr(_jit, "_PACKAGE", copy)

    def keys() -> dict[str, str]:
        _jit._source_hash.cache_clear()
        return {m: _jit._source_hash(f"scanlines.methods.{m}") for m in ALL_METHODS}

    before = keys()
    with (copy / "methods" / "hough.py").open("a") as source:
        source.write("\n# an edit\n")
    after_hough = keys()
    with (copy / "steps" / "fit.py").open("a") as source:
        source.write("\n# an edit\n")
    after_step = keys()
    _jit._source_hash.cache_clear()
    assert {m for m in ALL_METHODS if after_hough[m] != before[m]} == {"hough"}
    assert all(after_step[m] != after_hough[m] for m in ALL_METHODS)


@pytest.mark.parametrize("method", COMPILED_METHODS)
def test_the_compiled_methods_are_one_kernel(method):
    assert issubclass(method_class(method), CompiledMethod)
    scan = next(iter(open_log(sample("intel"))))
    assert len(Extractor(method)(scan)) > 0


def test_compilation_is_watched_from_before_numba_loads():
    # Commands watch compilation from their start without importing numba for it.
    code = (
        "import sys\n"
        "from scanlines._compile_watch import watch_compilation\n"
        "seen, done = [], []\n"
        "with watch_compilation(seen.append, lambda: done.append(True)):\n"
        "    loaded_before = 'numba' in sys.modules\n"
        "    import numba, scanlines._jit\n"
        "    twice = numba.njit(lambda x: 2 * x)\n"
        "    twice(3)\n"
        "twice(4.0)  # compiled after the watch: not seen\n"
        "print(loaded_before, seen, len(done))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip().split(maxsplit=1) == ["False", "['<lambda>'] 1"], out.stderr


def test_the_command_line_names_the_registered_methods_without_loading_them():
    from scanlines.builtin_methods import BUILTIN_METHODS
    from scanlines.methods import REGISTRY

    shipped = [n for n, method in REGISTRY.items() if method.__module__.startswith("scanlines.")]
    assert tuple(shipped) == BUILTIN_METHODS
    code = "import sys, scanlines.cli.commands; print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "False", out.stderr
