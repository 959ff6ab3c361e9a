"""The timing engine: how every time is taken, and ``scanlines bench`` (import the
modules by name; importing this package imports none of them)::

    timing      the one timing rule every time is taken by (eval, bench, the tools)
    machine     the machine a time was measured on
    measure     the speed of every method (scanlines bench): real and simulated scans,
                scaling over beam counts, Extractor.batch against the loop
    pipeline    the pipeline of scanlines run: stages, output formats, jobs, cold start
    config      what a bench run measures (BenchConfig)
    results     what a bench run measured, as JSON and tables

The repository's performance page (``docs/PERFORMANCE.md``) is written from the results
by its ``tools/bench``, which is not installed.
"""
