"""``scanlines map`` (plain and ``--align``) and ``scanlines localize`` write exactly the files
recorded in ``tests/records/map_outputs.json`` for the shipped excerpts.

The record was made with 960cdc6, before the filter's kernel was cut into its steps and
``build_map`` into its stages (``python tools/benchmarks/same_map_outputs.py record
tests/records/map_outputs.json``). A change meant to change these files re-records it in its
own commit and says why.
"""

from __future__ import annotations

import json
from pathlib import Path

from tools.benchmarks import same_map_outputs

RECORD = Path(__file__).parent / "records" / "map_outputs.json"


def test_every_file_is_identical():
    recorded = json.loads(RECORD.read_text())
    current = same_map_outputs.current()
    assert current.keys() == recorded.keys()
    differ = [name for name in recorded if current[name] != recorded[name]]
    assert not differ, f"{len(differ)} files differ: {', '.join(differ)}"
