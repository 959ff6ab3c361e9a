"""The compiler of the hot path: numba when installed, plain Python otherwise.

Every kernel (a function decorated :func:`kernel`) in :mod:`scanlines.steps` and
:mod:`scanlines.methods` is written once,
in the subset of Python and numpy that numba compiles. With numba (a dependency
of the package) the kernels are compiled on first use and cached next to the
sources' fingerprint; without it (or with ``NUMBA_DISABLE_JIT=1``) the same
functions run as ordinary Python: identical results, far slower.

The cache lives in a directory named by a hash of the kernels' sources: numba
checks only the file of the function it compiles, while a kernel inlines
kernels of other files, so a changed step must invalidate every kernel. It is
``$NUMBA_CACHE_DIR/scanlines-<hash>`` if that variable is set, else under
``$XDG_CACHE_HOME`` (default ``~/.cache``).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

try:
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None

__all__ = ["COMPILED", "cache_is_cold", "kernel"]

COMPILED = numba is not None and not numba.config.DISABLE_JIT


KERNEL_SOURCES = ("_jit.py", "steps/*.py", "methods/*.py")
"""The package files that hold kernels (the cache key hashes them)."""


def _source_hash() -> str:
    package = Path(__file__).parent
    digest = hashlib.sha1()
    for pattern in KERNEL_SOURCES:
        for path in sorted(package.glob(pattern)):
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _cache_dir() -> Path:
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "scanlines"
    )
    return Path(root) / f"numba-{_source_hash()}"


if numba is not None:
    numba.config.CACHE_DIR = str(_cache_dir())


def cache_is_cold() -> bool:
    """True when the kernels of this version have not been compiled on this machine yet."""
    return COMPILED and not any(Path(numba.config.CACHE_DIR).rglob("*.nbi"))


def kernel(function: F | None = None, *, inline: bool = False) -> Any:
    """Compile ``function`` with numba (cached, no Python objects), if available.

    Every function so decorated is a *kernel*: it takes arrays, scalars and the
    small bundles of :mod:`scanlines.steps` (named tuples, settings records), trusts
    them and validates nothing; validation happens once, in the public entry points.

    A kernel is compiled once per distinct set of argument types, and numba types a
    module constant passed as an argument as a literal of its own: pass
    ``np.int64(CONSTANT)`` where other callers pass a variable, or the kernel (and all
    it calls) is compiled twice.

    ``inline=True`` (as ``@kernel(inline=True)``) is for the small scalar helpers of
    the inner loops (a line fit from running sums, a threshold): numba calls
    between separately compiled functions are not inlined by LLVM, and such a
    call costs more than the helper's arithmetic.
    """
    if function is None:
        return lambda f: kernel(f, inline=inline)
    if numba is None:  # pragma: no cover
        return function
    options = {"inline": "always"} if inline else {}
    return numba.njit(cache=True, nogil=True, error_model="numpy", **options)(function)
