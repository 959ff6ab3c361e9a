"""``scanlines.bench.timing``: the one timing rule (the order of calls, not their speed)."""

from __future__ import annotations

import gc

import pytest

from scanlines.bench.timing import time_calls


def recorder(name: str, log: list[tuple[str, int]]):
    def call(item: int) -> str:
        log.append((name, item))
        return f"{name}({item})"

    return call


def test_every_timed_call_follows_an_untimed_call_on_the_same_item():
    log: list[tuple[str, int]] = []
    calls = {"a": recorder("a", log), "b": recorder("b", log)}
    timed = time_calls(calls, [1, 2], passes=2)
    one_pass = [("a", 1), ("a", 1), ("a", 2), ("a", 2), ("b", 1), ("b", 1), ("b", 2), ("b", 2)]
    assert log == one_pass * 2  # passes interleaved between the callables
    assert timed["a"].results == ["a(1)", "a(2)"]  # the first pass's untimed results
    assert timed["b"].samples_ns.shape == (2, 2)
    assert (timed["b"].samples_ns > 0).all()
    assert timed["b"].n_samples == 4


def test_a_failure_is_raised_or_recorded():
    def flaky(item: int) -> int:
        if item == 2:
            raise RuntimeError("boom\nsecond line")
        return item

    with pytest.raises(RuntimeError, match="boom"):
        time_calls({"f": flaky}, [1, 2, 3])
    ticks: list[str] = []
    timed = time_calls({"f": flaky}, [1, 2, 3], passes=2, catch=True, after_pass=ticks.append)
    failure = timed["f"].failure
    assert (failure.pass_index, failure.index) == (0, 1)
    assert failure.describe() == "scan 1: RuntimeError: boom"
    assert timed["f"].results == [1]
    assert timed["f"].n_samples == 1
    assert ticks == ["f", "f"]  # a failed callable still counts its passes


def test_the_collector_is_paused_while_timing_and_restored():
    seen: list[bool] = []
    time_calls({"c": lambda _: seen.append(gc.isenabled())}, [0])
    assert seen == [False, False]
    assert gc.isenabled()
