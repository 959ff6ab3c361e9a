"""Every parameter of every method declares its domain, and every value outside it is a
ParameterError before anything runs (never OverflowError, MemoryError or a kernel
failure); values on the domain's edges are accepted."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import scanlines
from scanlines import Extractor, ParameterError, method_info

PARAMETERS = [
    (method, name, param)
    for method in scanlines.method_names()
    for name, param in method_info(method).params.items()
]
IDS = [f"{method}.{name}" for method, name, _ in PARAMETERS]
ANY_TYPE_WRONG = [math.inf, -math.inf, math.nan, 1j, [1.0], {"a": 1}, object(), b"1", "inf"]


def outside(domain: dict) -> list:
    """Values just outside ``domain`` and far outside it."""
    kind = domain["type"]
    if kind == "choice":
        return ["no such choice", 12345, None if None not in domain["choices"] else "x"]
    if kind == "pair":
        low, high = domain["element"]["low"], domain["element"]["high"]
        return [(1.0,), (2.0, 1.0), (low - 1.0, low + 1.0), (low, high * 2), "a,b", 3.0]
    low, high = domain["low"], domain["high"]
    values = [low - 1, high + 1, high * 10, 10**30, -(10**30), 1e308, -1e308]
    if kind == "int":
        values += [low + 0.5, "1.5", True]
    if domain.get("low_open"):
        values.append(low)
    return values


def inside(domain: dict) -> list:
    kind = domain["type"]
    if kind == "choice":
        return list(domain["choices"])
    if kind == "pair":
        low, high = domain["element"]["low"], domain["element"]["high"]
        return [(low, high), f"{low},{high}"]
    low, high = domain["low"], domain["high"]
    values = [high, str(high)]
    if not domain.get("low_open"):
        values.append(low)
    if kind == "int":
        values.append(float(low + 1))
    return values


def accepts(method: str, name: str, value) -> bool:
    try:
        Extractor(method, **{name: value})
    except ParameterError:
        return False
    return True


@pytest.mark.parametrize(("method", "name", "param"), PARAMETERS, ids=IDS)
def test_every_value_outside_the_domain_is_a_parameter_error(method, name, param) -> None:
    domain = param.domain
    word = domain.get("or", "no word")
    for value in [*ANY_TYPE_WRONG, *outside(domain)]:
        if value == word or (isinstance(value, str) and value.lower() in ("none", "off")):
            continue
        assert not accepts(method, name, value), (value, param.allowed)


@pytest.mark.parametrize(("method", "name", "param"), PARAMETERS, ids=IDS)
def test_the_domain_edges_are_accepted(method, name, param) -> None:
    for value in inside(param.domain):
        assert accepts(method, name, value), (value, param.allowed)
    if "or" in param.domain:
        assert accepts(method, name, param.domain["or"])


NUMBERS = [(m, n, p) for m, n, p in PARAMETERS if p.domain["type"] in ("int", "float")]


@settings(max_examples=300, deadline=None)
@given(
    case=st.sampled_from(NUMBERS),
    value=st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(10**40), max_value=10**40),
        st.text(max_size=8),
    ),
)
def test_any_number_is_accepted_exactly_when_inside(case, value) -> None:
    method, name, param = case
    domain = param.domain
    try:
        number = float(value)
    except (ValueError, OverflowError):
        number = math.nan
    low_ok = number > domain["low"] if domain.get("low_open") else number >= domain["low"]
    inside_bounds = math.isfinite(number) and low_ok and number <= domain["high"]
    if domain["type"] == "int" and inside_bounds:
        inside_bounds = float(number).is_integer() and not (
            isinstance(value, str) and "." in value and not value.strip().endswith(".0")
        )
    is_word = isinstance(value, str) and value.strip().lower() in ("auto", "none", "off")
    if is_word or (isinstance(value, str) and inside_bounds):
        return  # words and numeric strings: covered above (parsing rules differ)
    assert accepts(method, name, value) == inside_bounds, (value, param.allowed)


def test_method_info_prints_a_readable_table() -> None:
    text = str(method_info("ransac"))
    assert text.splitlines()[0].startswith("ransac: ")
    assert "trials" in text
    assert "an integer in [1, 10000]" in text
    assert "presets:" in text


def test_help_of_extract_documents_its_parameters() -> None:
    doc = scanlines.extract.__doc__
    for word in ("method", "preset", "sensor_profile", "method_info", "ParameterError"):
        assert word in doc


# -- domains that hold at run time (not only at construction) --------------------------------


def test_hough_rho_resolution_is_bounded_so_that_its_grid_fits():
    """5e-324 m made the number of rho cells infinite: OverflowError at extraction."""
    from scanlines.data import sample
    from scanlines.io import open_log
    from scanlines.methods.hough import MAX_RHO_RESOLUTION, MIN_RHO_RESOLUTION

    for tiny in (5e-324, 1e-300, MIN_RHO_RESOLUTION / 2):
        with pytest.raises(ParameterError, match="rho_resolution"):
            Extractor("hough", rho_resolution=tiny)
    with open_log(sample("intel")) as reader:
        scan = next(iter(reader))
    for edge in (MIN_RHO_RESOLUTION, MAX_RHO_RESOLUTION):
        assert Extractor("hough", rho_resolution=edge)(scan).segments is not None


def test_a_profile_noise_beyond_1_m_plus_100_percent_is_refused(tmp_path):
    from scanlines.sensor.profile import ProfileError, SensorProfile, read_profile

    def written(sigma0: float, per_metre: float):
        path = tmp_path / "p.json"
        SensorProfile(sigma0, per_metre, beams=180, scans=10).save(path)
        return path

    assert read_profile(written(1.0, 1.0)).noise_sigma0 == 1.0
    for sigma0, per_metre in ((1e300, 0.0), (0.0, 1e300), (1.001, 0.0), (0.0, 1.001)):
        with pytest.raises(ProfileError, match="at most 1 m \\+ 100 % of range") as caught:
            read_profile(written(sigma0, per_metre))
        assert len(str(caught.value).splitlines()) == 1


def test_an_angle_increment_that_rounds_to_0_in_float32_is_refused():
    from scanlines import Scan
    from scanlines.errors import ScanError

    for tiny in (1e-46, -1e-46, 5e-324):
        with pytest.raises(ScanError, match=r"angle_increment .* rounds to 0 in float32"):
            Scan([1.0] * 112, 0.0, tiny)
    assert Scan([1.0] * 112, 0.0, 1.5e-45).angle_increment == 1.5e-45  # float32's least
