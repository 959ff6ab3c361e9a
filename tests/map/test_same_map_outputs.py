"""``scanlines map`` (plain and ``--align``), ``localize`` and ``eval map`` write the files
recorded in ``tests/records/map_outputs.json`` for the shipped excerpts.

The record was made with 960cdc6, before the filter's kernel was cut into its steps,
``build_map`` into its stages and the map's settings tables moved to ``params`` (each
move left every file the same bytes; the runs of ``--min-scans 2`` and ``eval map`` were
checked by a record of their own); then again after the one point-to-line linearisation
(f3c4b76), which moved the last digits of 10 files (covariances, map JSON), none by more
than a relative 1e-9. Recorded with ``python tools/benchmarks/same_map_outputs.py record
tests/records/map_outputs.json``; a change meant to change these files re-records it in
its own commit and says why.
"""

from __future__ import annotations

from pathlib import Path

from tools.benchmarks import same_map_outputs

RECORD = Path(__file__).parents[1] / "records" / "map_outputs.json"


def test_every_file_is_the_same():
    """The same text and numbers (to a relative 1e-9: another BLAS sums in another order);
    on the machine that recorded it, the same bytes (``same_map_outputs.py compare``)."""
    recorded = same_map_outputs.read_record(RECORD)
    found = same_map_outputs.current()
    assert found[0].keys() == recorded[0].keys()
    differ = same_map_outputs.beyond_rounding(recorded, found)
    assert not differ, f"{len(differ)} files differ: {', '.join(differ)}"
