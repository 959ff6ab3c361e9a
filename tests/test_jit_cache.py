"""The first-run note: shown while the kernels of this version are not compiled yet."""

from __future__ import annotations

import os
import subprocess
import sys

CODE = (
    "import numba; from scanlines import _jit; from pathlib import Path; "
    "print(_jit.cache_is_cold()); "
    "folder = Path(numba.config.CACHE_DIR) / 'scanlines_steps_fit'; "
    "folder.mkdir(parents=True); (folder / 'fit.tls_run-1.py311.nbi').write_bytes(b''); "
    "print(_jit.cache_is_cold())"
)


def test_cache_is_cold_until_a_kernel_is_cached(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run(
        [sys.executable, "-c", CODE], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.split() == ["True", "False"]
