"""The parameters the viewer hides (``Param.applies``) are the ones a method does not read:
changing one that does not apply changes no feature."""

from __future__ import annotations

import pytest

from scanlines import Extractor, method_names
from scanlines.data import sample
from scanlines.extractor import method_class, method_info
from scanlines.io import open_log
from scanlines.params import param_applies

#: Values of each deciding parameter to try: under some, the rule's parameter is not read.
VALUES = {
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


def _rules() -> list[tuple[str, str, str]]:
    """(method, parameter, the parameter deciding it) of every rule a method keeps."""
    return [
        (method, name, info.applies[0])
        for method in method_names()
        for name, info in method_info(method).params.items()
        if info.applies is not None
    ]


CASES = [
    (method, name, other, value)
    for method, name, other in _rules()
    for value in VALUES[other]
    if not param_applies(method_class(method).parameters[name], {other: value})
    and _allowed(method, other, value)
]


@pytest.mark.parametrize(("method", "name", "other", "value"), CASES)
def test_a_parameter_that_does_not_apply_changes_nothing(method, name, other, value, scans):
    base = Extractor(method, **{other: value})
    changed = Extractor(method, **{other: value, name: OTHER_VALUE[name]})
    assert _features(base, scans) == _features(changed, scans)


def test_the_rules_are_kept_where_the_method_has_the_deciding_parameter():
    assert {name for _, name, _, _ in CASES} == set(OTHER_VALUE)
    assert method_info("paper").params["window"].applies is None  # no denoise choice
    assert method_info("adaptive").params["window"].applies == ("denoise", ("paper",), True)
    assert method_info("split_merge").params["jump_distance"].applies is not None
