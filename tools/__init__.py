"""The repository's own lab, not installed: the pages it writes, benchmarks, experiments.

``python -m tools.reproduce`` writes ``docs/RESULTS.md``, ``python -m tools.bench``
``docs/PERFORMANCE.md``; ``tools/benchmarks/`` and ``tools/decisions/`` hold the scripts
behind the figures of the other pages. Run them from the repository's root.
"""
