"""A parameter declared once gives its domain, its file spelling and its kernel fields."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest

from scanlines import Extractor, method_info
from scanlines.config import ExtractionConfig, load_config
from scanlines.methods import REGISTRY, CompiledMethod, register, unregister
from scanlines.params import (
    GROUPS,
    Param,
    as_float,
    auto_or,
    choice,
    coded,
    flag,
    kernel_settings,
    number,
    optional,
    radians,
)
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import CLUSTERING, NO_RULE, RULE_CODES, RuleSpec
from scanlines.steps.events import EVENTS


class Declared(CompiledMethod):
    """A compiled method that is only its declarations (it is built, never run)."""

    name = "declared_settings"
    parameters: ClassVar[dict[str, Param]] = {
        **output_settings(4),
        "turn": Param(30.0, number(low=0.0, high=90.0), "a turn (deg)", (radians(),)),
        "side": Param("left", choice("left", "right"), "a side", (coded({"left": 0, "right": 1}),)),
        "bound": Param(None, optional(number(low=0.0)), "a bound (m), or none"),
        "width": Param(
            "auto",
            auto_or(number(low=0.0, low_open=True)),
            "a width (m), or auto",
            (as_float(), flag("auto_width", "auto")),
        ),
        "quiet": Param(True, choice(True, False), "a switch"),
    }
    built: ClassVar[int] = 0

    def __init__(self, params, noise=None) -> None:
        super().__init__(params, noise)
        Declared.built += 1


@pytest.fixture
def declared():
    register(Declared)
    yield Declared
    unregister(Declared.name)


def test_a_declared_parameter_reaches_method_info_the_file_and_the_record(declared, tmp_path):
    info = method_info(declared.name).params
    assert list(info) == list(declared.parameters)
    assert info["turn"].domain == {"type": "float", "low": 0.0, "high": 90.0, "low_open": False}
    assert info["side"].domain == {"type": "choice", "choices": ["left", "right"]}
    config = ExtractionConfig(declared.name, params={"turn": 45, "side": "right", "bound": None})
    path = tmp_path / "declared.toml"
    path.write_text(config.to_toml())
    assert 'bound = "none"' in config.to_toml().splitlines()
    Declared.built = 0
    assert load_config(path) == config
    assert Declared.built == 1  # the file is validated once
    settings = config.extractor()._method.record
    assert list(settings) == [
        *("min_points", "min_length", "range_sigma", "turn", "side", "bound", "width"),
        *("auto_width", "quiet"),
    ]
    assert settings["turn"] == math.radians(45.0)
    assert (settings["side"], settings["bound"], settings["quiet"]) == (1, math.inf, True)
    assert math.isnan(settings["width"])
    assert settings["auto_width"]
    # plain Python numbers, the only form the compiled kernels read (no numpy scalars)
    assert type(settings["side"]) is int
    assert type(settings["auto_width"]) is bool
    assert type(settings["turn"]) is float


def test_a_string_choice_without_declared_fields_is_refused():
    spec = {"side": Param("left", choice("left", "right"), "a side")}
    with pytest.raises(TypeError, match="declare the kernel fields"):
        kernel_settings(spec, {"side": "left"})


@pytest.mark.parametrize(
    "name", [n for n, cls in REGISTRY.items() if issubclass(cls, CompiledMethod)]
)
def test_every_record_field_of_a_builtin_method_comes_from_a_declaration(name):
    cls = REGISTRY[name]
    params = Extractor(name).params
    record = cls.record_of(params)
    assert list(record) == list(GROUPS)
    for group, spec in cls.settings.groups().items():
        declared = kernel_settings(spec, params)
        settings = record[group]
        assert set(settings) - set(declared) <= {"split_reference"}  # the split methods' own
        for field, value in declared.items():  # NaN fields included
            assert np.array_equal(settings[field], value, equal_nan=True), field
            assert np.asarray(settings[field]).dtype == np.asarray(value).dtype, field


def test_the_rule_and_output_tuples_are_the_fields_of_their_parameter_groups():
    assert set(RuleSpec._fields) == set(CLUSTERING)
    line_tracking = Extractor("line_tracking", abd_lambda=20.0, corner_angle=30.0)._method
    assert line_tracking.rule.abd_lambda == math.radians(20.0)
    assert line_tracking.output.corner_angle == math.radians(30.0)
    assert math.isnan(Extractor("ransac", range_sigma="auto")._method.output.range_sigma)
    assert set(EVENTS) <= set(line_tracking.output._fields)
    assert line_tracking.rule.breakpoints == RULE_CODES["fixed"]
    assert Extractor("ransac")._method.rule.breakpoints == NO_RULE
