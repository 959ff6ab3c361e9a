"""The parameters the viewer hides (``scanlines.params.APPLIES_WHEN``) are the ones a
method does not read: changing one that does not apply changes no feature."""

from __future__ import annotations

import pytest

from scanlines import Extractor, method_names
from scanlines.data import sample
from scanlines.extractor import method_info
from scanlines.io import open_log
from scanlines.params import APPLIES_WHEN, param_applies

#: A value of each governing parameter under which the rule's parameter is not read.
NOT_READ_WITH = {
    "breakpoints": ["paper", "abd", "pdbs", "fixed"],
    "denoise": ["none", "paper", "isolated"],
    "corner_score": ["dk", "turn"],
    "dkth_range": ["auto", (0.1, 2.0)],
    "merge": [False, True],
}
#: Another allowed value of each rule's parameter, far from its default.
OTHER_VALUE = {
    "k": 9.0, "noise_k": 9.0, "abd_lambda": 40.0, "pdbs_c0": 0.5, "jump_distance": 0.02,
    "window": 7, "min_cluster_points": 9, "slope_window": 9, "dkth_step": 0.5,
    "merge_chi2": 0.01,
}  # fmt: skip


@pytest.fixture(scope="module")
def scans():
    with open_log(sample("intel")) as reader:
        return [scan for _, scan in zip(range(8), reader, strict=False)]


def _features(extractor, scans) -> list:
    out = []
    for scan in scans:
        found = extractor(scan)
        out.append((found.breakpoints.tolist(), found.corners.tolist(), len(found.segments)))
    return out


def _allowed(method: str, name: str, value) -> bool:
    try:
        Extractor(method, **{name: value})
    except ValueError:
        return False
    return True


CASES = [
    (method, name, governing, value)
    for method in method_names()
    for name, (governing, _, _) in APPLIES_WHEN.items()
    if name in method_info(method).params and governing in method_info(method).params
    for value in NOT_READ_WITH[governing]
    if not param_applies(name, {governing: value}) and _allowed(method, governing, value)
]


@pytest.mark.parametrize(("method", "name", "governing", "value"), CASES)
def test_a_parameter_that_does_not_apply_changes_nothing(method, name, governing, value, scans):
    base = Extractor(method, **{governing: value})
    other = Extractor(method, **{governing: value, name: OTHER_VALUE[name]})
    assert _features(base, scans) == _features(other, scans)


def test_every_rule_is_checked_on_some_method():
    assert {name for _, name, _, _ in CASES} == set(APPLIES_WHEN)
