"""The kernels are one implementation: compiled and plain-Python runs agree exactly.

``NUMBA_DISABLE_JIT=1`` runs every kernel as ordinary Python, which is also what
the package does when numba is not installed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from scanlines import Extractor, _jit
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


def test_cache_directory_is_keyed_by_the_sources(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    directory = _jit._cache_dir()
    assert directory.parent == tmp_path
    assert directory.name == f"numba-{_jit._source_hash()}"


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
