"""The one way extraction times are taken: :func:`time_calls`.

``scanlines eval``, ``scanlines bench`` and the repository's tools all time through
this module, by one rule:

* **A sample** is the wall time of one call on one scan (:func:`time.perf_counter_ns`),
  reported in microseconds.
* **Every timed call directly follows an untimed call of the same callable on the same
  scan**, and the untimed call's result is the one returned (and scored). The untimed
  call takes the one-off costs (compiling or loading a kernel, lazy imports, bearing
  tables) and brings the method's code and the scan's data into the processor's caches,
  so a sample does not depend on what ran just before it: generating a scene, scoring,
  another method. (Before this rule one eval run measured the same configuration under
  two labels at 155 and 73 us per scan, depending on its place in the list.)
* **Passes** over the scans (``passes`` of them) are interleaved between the callables:
  pass 1 of every callable, then pass 2, ..., so that a slow drift of the machine spreads
  over all of them.
* The garbage collector is paused while the calls run, so that no collection lands in a
  sample.

``eval`` makes one pass per scene (every spec on the scene's scan, one sample each);
``reproduce`` and ``bench`` make ``repeats`` passes over each dataset. Ratios of times
refer to :data:`REFERENCE`, the method the paper compares against.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

__all__ = ["REFERENCE", "Failure", "Timed", "time_calls"]

REFERENCE = "iepf"
"""The method time ratios refer to (the paper's comparison); below 1 is faster."""

Key = TypeVar("Key", bound=Hashable)
Item = TypeVar("Item")
Result = TypeVar("Result")


@dataclass(frozen=True)
class Failure:
    """The exception that stopped a callable: on which pass and item."""

    pass_index: int
    index: int
    error: BaseException

    def describe(self) -> str:
        """``scan INDEX: TYPE: first line of the message``, at most 300 characters."""
        message = str(self.error).splitlines()[0] if str(self.error) else ""
        return f"scan {self.index}: {type(self.error).__name__}: {message}"[:300]


@dataclass(frozen=True, eq=False)
class Timed(Generic[Result]):
    """What :func:`time_calls` measured of one callable.

    Attributes
    ----------
    results:
        What the untimed calls of the first pass returned, one per item (up to a failure).
    samples_ns:
        ``(passes, items)`` timed samples in nanoseconds (0 where nothing was timed).
    failure:
        The exception that stopped the callable, when ``catch`` was set.
    """

    results: list[Result]
    samples_ns: np.ndarray
    failure: Failure | None = None

    @property
    def n_samples(self) -> int:
        """Samples taken (all of them, or those before the failure)."""
        if self.failure is None:
            return self.samples_ns.size
        return self.failure.pass_index * self.samples_ns.shape[1] + self.failure.index


def time_calls(
    calls: Mapping[Key, Callable[[Item], Result]],
    items: Sequence[Item],
    passes: int = 1,
    *,
    catch: bool = False,
    after_pass: Callable[[Key], None] | None = None,
) -> dict[Key, Timed[Result]]:
    """Time every callable on every item by the rule of the module docstring.

    Parameters
    ----------
    calls:
        ``key -> callable(item)``, timed in this order within each pass.
    items:
        What the callables are called on (scans, scenes).
    passes:
        Timed passes over ``items``.
    catch:
        Record an exception as the callable's :attr:`Timed.failure` and stop calling it,
        instead of raising it.
    after_pass:
        Called with the key after each pass of each callable (a failed one included).
    """
    results: dict[Key, list[Any]] = {key: [] for key in calls}
    samples = {key: np.zeros((passes, len(items)), np.int64) for key in calls}
    failures: dict[Key, Failure] = {}
    with _collector_paused():
        for p in range(passes):
            for key, call in calls.items():
                if key not in failures:
                    kept = results[key] if p == 0 else None
                    failed = _one_pass(call, items, samples[key][p], kept)
                    if failed is not None:
                        index, error = failed
                        if not catch:
                            raise error
                        failures[key] = Failure(p, index, error)
                if after_pass is not None:
                    after_pass(key)
    return {key: Timed(results[key], samples[key], failures.get(key)) for key in calls}


def _one_pass(
    call: Callable[[Any], Any], items: Sequence[Any], row: np.ndarray, kept: list | None
) -> tuple[int, Exception] | None:
    """One timed pass into ``row``; the untimed results go to ``kept``. Returns a failure."""
    clock = time.perf_counter_ns
    for i, item in enumerate(items):
        try:
            result = call(item)
            start = clock()
            call(item)
            row[i] = clock() - start
        except Exception as error:
            return i, error
        if kept is not None:
            kept.append(result)
    return None


@contextmanager
def _collector_paused() -> Iterator[None]:
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
