"""Every configuration gives exactly the features recorded in ``tests/records/features.npz``.

The record was made with the numba kernels of 4425bd7, before the kernels moved to C++
(``python tools/benchmarks/same_features.py record tests/records/features.npz -n 8 --real
15``). A change meant to change features re-records it in its own commit and says why.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tools.benchmarks import same_features

RECORD = Path(__file__).parent / "records" / "features.npz"


@pytest.fixture(scope="module")
def recorded_and_current():
    with np.load(RECORD) as stored:
        recorded = dict(stored)
    real = int(recorded.pop("meta|real"))
    sets = same_features.scans(int(recorded.pop("meta|n")), None if real < 0 else real)
    return recorded, same_features.features(sets), sets


def test_every_array_is_identical(recorded_and_current):
    recorded, current, sets = recorded_and_current
    found = same_features.differences(recorded, current)
    shown = [same_features.first_difference(recorded, current, key, sets) for key in found[:10]]
    assert not found, f"{len(found)} arrays differ, first: " + "\n".join(shown)


def test_the_record_covers_every_configuration(recorded_and_current):
    recorded, _, _ = recorded_and_current
    labels = {key.split("|")[0] for key in recorded}
    for label, *_ in same_features.configurations():
        assert label in labels
    assert any(key.endswith("|batch|end_kinds") for key in recorded)
    assert any(key.endswith("|profile|lines") for key in recorded)
    assert recorded["partition:|urg|first|rows"].shape[0] == 15
