"""The sample logs shipped in scanlines.data."""

from __future__ import annotations

import gzip
import hashlib
import re

import pytest

from scanlines.data import SAMPLES, provenance, sample


def test_sample_paths_exist() -> None:
    assert sample("intel").name == "intel_excerpt.clf.gz"
    assert sample("freiburg").name == "fr079_excerpt.log.gz"
    assert all(sample(name).is_file() for name in SAMPLES)


def test_unknown_sample_lists_the_valid_names() -> None:
    with pytest.raises(ValueError, match="unknown sample 'mit'; samples: 'intel', 'freiburg'"):
        sample("mit")


def test_samples_are_small() -> None:
    assert sum(sample(name).stat().st_size for name in SAMPLES) < 2_000_000


@pytest.mark.parametrize("name", list(SAMPLES))
def test_provenance_records_the_sha256(name) -> None:
    path = sample(name)
    row = next(
        line for line in provenance().splitlines() if f"`{path.name}`" in line and "|" in line
    )
    recorded = re.findall(r"`([0-9a-f]{64})`", row)
    assert recorded == [hashlib.sha256(path.read_bytes()).hexdigest()]


def test_provenance_credits_recorders_and_sources() -> None:
    text = provenance()
    for needle in ("Dirk Hähnel", "Cyrill Stachniss", "Radish", "evlgroup/SOT", "ROB312", "sha256"):
        assert needle in text


@pytest.mark.parametrize(("name", "note_line"), [("intel", 6), ("freiburg", 12)])
def test_excerpts_say_they_are_excerpts(name, note_line) -> None:
    with gzip.open(sample(name), "rt") as fh:
        lines = [next(fh) for _ in range(note_line)]
    assert lines[-1].startswith("# scanlines excerpt")
    assert "PROVENANCE.md" in lines[-1]
