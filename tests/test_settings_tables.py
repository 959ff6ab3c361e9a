"""The settings tables of the map and the registration (``scanlines.params.tables``): every
setting declares its domain, every value outside it is a one-line ParameterError naming the
setting, and a table behaves as the frozen dataclass it replaced (keywords, attributes,
``to_dict``, equality, copies)."""

from __future__ import annotations

import copy
import importlib
import pickle
import pkgutil
from dataclasses import FrozenInstanceError
from typing import ClassVar

import pytest

import scanlines.geometry
import scanlines.map
import scanlines.sensor
from scanlines import ParameterError
from scanlines.geometry.registration import IcpSettings
from scanlines.map.align import AlignSettings
from scanlines.map.filter import FilterSettings
from scanlines.map.fusion import FusionSettings
from scanlines.map.loops import LoopSettings
from scanlines.map.relocalise import SearchSettings
from scanlines.map.tracking import TrackSettings
from scanlines.params import Param, integer, number
from scanlines.params.tables import Groups, SettingsTable
from test_parameter_domains import ANY_TYPE_WRONG, inside, outside

TABLES = (
    IcpSettings,
    AlignSettings,
    FusionSettings,
    SearchSettings,
    TrackSettings,
    FilterSettings,
    LoopSettings,
)
SETTINGS = [(table, name) for table in TABLES for name in table.parameters]
IDS = [f"{table.__name__}.{name}" for table, name in SETTINGS]


def declared_tables() -> set[type[SettingsTable]]:
    """The settings tables the map, geometry and sensor packages declare."""
    found = set()
    for package in (scanlines.map, scanlines.geometry, scanlines.sensor):
        for module in pkgutil.iter_modules(package.__path__, package.__name__ + "."):
            for value in vars(importlib.import_module(module.name)).values():
                if isinstance(value, type) and issubclass(value, SettingsTable):
                    found.add(value)
    return found - {SettingsTable}


def test_every_table_of_the_package_is_checked_here():
    assert declared_tables() == set(TABLES)


def one_line_error(table: type[SettingsTable], name: str, value) -> ParameterError:
    with pytest.raises(ParameterError) as caught:
        table(**{name: value})
    error = caught.value
    assert "\n" not in str(error), str(error)
    assert error.parameter == name
    return error


@pytest.mark.parametrize(("table", "name"), SETTINGS, ids=IDS)
def test_a_value_outside_the_domain_is_one_line_naming_the_setting(table, name):
    domain = table.parameters[name].check.domain()
    for value in [*outside(domain), *ANY_TYPE_WRONG]:
        error = one_line_error(table, name, value)
        assert str(error).startswith(f"{table.__name__}.{name} must be"), str(error)


@pytest.mark.parametrize(("table", "name"), SETTINGS, ids=IDS)
def test_the_domain_edges_are_accepted(table, name):
    domain = table.parameters[name].check.domain()
    for value in inside(domain):
        if table is IcpSettings and name == "min_distance" and float(value) > 0.5:
            continue  # at most max_distance: test_a_relation_between_settings
        if table is FilterSettings and name == "gate_min" and float(value) > 0.5:
            continue  # at most gate_max: test_a_relation_between_settings
        made = table(**{name: value})
        assert getattr(made, name) == table.parameters[name].check(name, value)


def test_an_unknown_setting_lists_the_valid_ones():
    error = one_line_error(FusionSettings, "min_scan", 2)
    assert str(error).startswith("unknown setting(s) min_scan of FusionSettings; valid: gate,")


def test_a_relation_between_settings():
    error = one_line_error(IcpSettings, "min_distance", 0.6)
    assert str(error) == "IcpSettings.min_distance must be at most max_distance (0.5), got 0.6"
    assert IcpSettings(min_distance=0.6, max_distance=0.6).min_distance == 0.6
    error = one_line_error(FilterSettings, "gate_min", 0.6)
    assert str(error) == "FilterSettings.gate_min must be at most gate_max (0.5), got 0.6"


@pytest.mark.parametrize("table", TABLES, ids=lambda t: t.__name__)
def test_a_table_is_the_frozen_dataclass_it_replaced(table):
    made = table()
    assert list(made.to_dict()) == list(table.parameters)
    assert made.to_dict() == {name: p.default for name, p in table.parameters.items()}
    assert made == table()
    assert hash(made) == hash(table())
    assert pickle.loads(pickle.dumps(made)) == made == copy.deepcopy(made) == copy.copy(made)
    assert eval(repr(made), {table.__name__: table}) == made
    name, param = next(iter(table.parameters.items()))
    with pytest.raises(FrozenInstanceError):
        setattr(made, name, param.default)
    other = next(v for v in inside(param.check.domain()) if param.check(name, v) != param.default)
    changed = made.replace(**{name: other})
    assert changed != made
    assert getattr(made, name) == param.default
    assert changed.to_dict() == {**made.to_dict(), name: param.check(name, other)}
    assert all(
        isinstance(v, bool | int | float) for g in made.record().values() for v in g.values()
    )


def test_keyword_construction_keeps_the_types_outputs_record():
    assert FusionSettings(min_scans=2).to_dict()["min_scans"] == 2
    assert type(FusionSettings(min_scans="2").min_scans) is int  # from the command line
    assert type(TrackSettings(iterations=4.0).iterations) is int
    assert FusionSettings().chi2 == 9.210
    assert FusionSettings(gate=0.95).chi2 == 5.991
    assert FusionSettings().record()["association"] == {"chi2": 9.210, "max_gap": 0.5}
    assert SearchSettings(lost_after=10**9).lost_after == 10**9  # "never" (localize_speed.py)


@pytest.mark.parametrize("table", TABLES, ids=lambda t: t.__name__)
def test_every_setting_is_documented_in_the_docstring(table):
    assert "settings (default; allowed values):" in table.__doc__
    for group, params in table.groups.items():
        assert f"\n {group}:\n" in table.__doc__
        for name, param in params.items():
            assert param.doc
            assert "\n" not in param.doc
            assert f"  {name} " in table.__doc__


def test_a_mistaken_declaration_fails_when_the_class_is_made():
    three = Param(3, integer(1, 10), "three")
    with pytest.raises(TypeError, match="'a' is in two groups"):

        class Twice(SettingsTable):
            groups: ClassVar[Groups] = {"one": {"a": three}, "two": {"a": three}}

    with pytest.raises(TypeError, match="'replace' hides an attribute"):

        class Hiding(SettingsTable):
            groups: ClassVar[Groups] = {"one": {"replace": three}}

    with pytest.raises(TypeError, match=r"declare b's default as 3\.0"):

        class Untyped(SettingsTable):
            groups: ClassVar[Groups] = {"one": {"b": Param(3, number(), "an int for a float")}}

    with pytest.raises(TypeError, match=r"c.s default: Bad\.c must be an integer in"):

        class Bad(SettingsTable):
            groups: ClassVar[Groups] = {"one": {"c": Param(0, integer(1, 10), "outside")}}
