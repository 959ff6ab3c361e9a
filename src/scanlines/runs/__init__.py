"""Whole logs through an extractor (import the modules by name; importing this package
imports none of them)::

    runner      one log: describe it, extract every scan in chunks on threads, write the
                results (scanlines run, info)
    fleet       many logs as chunk tasks on local processes or a Dask cluster, into one
                Parquet dataset (scanlines run DIR --format parquet; run_fleet, fleet_tasks)
    inputs      the logs a fleet run reads: folders, globs, files
    executors   where a fleet run's tasks run: a process pool or a Dask cluster
"""
