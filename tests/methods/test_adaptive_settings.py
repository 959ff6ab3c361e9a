"""adaptive's settings are read once, into the steps they select, and travel a short way.

``adaptive_steps`` reads every switch of the settings record (``fit == PAPER``,
``criterion == BIC``, ...) once per stack; ``adaptive_scan`` hands each stage its own group of
the result. The walk follows that record (or a part of it: a group, a field, a local name
bound to one) from ``adaptive_scan`` into every kernel function it is passed to, read from
the C++ sources by ``tests/cpp_sources.py``.
"""

from __future__ import annotations

import re

import cpp_sources

ADAPTIVE = cpp_sources.CPP / "scanlines" / "methods" / "adaptive.cpp"
MOST_FUNCTIONS = 30


def _walk() -> list[tuple[str, str]]:
    return cpp_sources.settings_walk(cpp_sources.all_functions("scanlines"), "adaptive_scan", "s")


def test_the_settings_reach_at_most_30_functions():
    reached = {callee for _, callee in _walk()} | {"adaptive_scan"}
    assert len(reached) <= MOST_FUNCTIONS, sorted(reached)


def test_the_walk_follows_groups_fields_and_aliases():
    """The reader finds what it must: a group handed on (denoise's fields), a group's
    field passed further (the fit into fit_run), a local alias (breakpoint_rule's rule)."""
    stops = set(_walk())
    assert ("adaptive_scan", "denoise") in stops
    assert ("split_by_residual", "fit_run") in stops
    assert ("breakpoint_rule", "make_rule") in stops


def test_only_adaptive_steps_reads_the_switches():
    switch = re.compile(r"[!=]=\s*(PAPER|BIC)\b|\b(PAPER|BIC)\s*[!=]=")
    readers = {
        function.name
        for function in cpp_sources.functions(ADAPTIVE)
        if switch.search(function.body)
    }
    assert readers == {"adaptive_steps"}
    # The record's segments, events and output groups hold the switches of several stages:
    # only adaptive_steps reads them.
    group = re.compile(r"\.(segments|events|output)\.")
    readers = {
        function.name for function in cpp_sources.functions(ADAPTIVE) if group.search(function.body)
    }
    assert readers == {"adaptive_steps"}


def test_adaptive_scan_reads_like_its_stages():
    (scan,) = [f for f in cpp_sources.functions(ADAPTIVE) if f.name == "adaptive_scan"]
    assert scan.lines <= 70
    assert "Laps" not in scan.body
    assert "seconds" not in scan.body
