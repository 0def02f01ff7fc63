"""Unit normalisation: every alias against independent constants, refusals, spelling variants."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.errors import UnitError
from pipeline.units import ALIASES, QUANTITIES, canonical_unit, conversion_factor

FT = 0.3048
US_FT = 1200 / 3937
DEG = 1.0
RAD = 180 / math.pi  # deg per rad
G0 = 9.80665

EXPECTED: dict[str, tuple[str, float]] = {
    "M": ("length", 1.0),
    "METER": ("length", 1.0),
    "METERS": ("length", 1.0),
    "METRE": ("length", 1.0),
    "METRES": ("length", 1.0),
    "F": ("length", FT),
    "FT": ("length", FT),
    "FEET": ("length", FT),
    "FOOT": ("length", FT),
    "USFT": ("length", US_FT),
    "US-FT": ("length", US_FT),
    "ftUS": ("length", US_FT),
    "IN": ("length", 0.0254),
    "INCH": ("length", 0.0254),
    "INCHES": ("length", 0.0254),
    "M2": ("area", 1.0),
    "M^2": ("area", 1.0),
    "m²": ("area", 1.0),
    "FT2": ("area", FT * FT),
    "FT^2": ("area", FT * FT),
    "ft²": ("area", FT * FT),
    "DEG": ("angle", DEG),
    "DEGA": ("angle", DEG),
    "DEGREE": ("angle", DEG),
    "DEGREES": ("angle", DEG),
    "°": ("angle", DEG),
    "RAD": ("angle", RAD),
    "RADIAN": ("angle", RAD),
    "RADIANS": ("angle", RAD),
    "°/100'": ("dogleg_severity", 30 / (100 * FT)),
    "°/100FT": ("dogleg_severity", 30 / (100 * FT)),
    "DEG/100'": ("dogleg_severity", 30 / (100 * FT)),
    "DEG/100FT": ("dogleg_severity", 30 / (100 * FT)),
    "°/30M": ("dogleg_severity", 1.0),
    "DEG/30M": ("dogleg_severity", 1.0),
    "DEG/H": ("angular_rate", 1.0),
    "DEG/HR": ("angular_rate", 1.0),
    "°/H": ("angular_rate", 1.0),
    "°/HR": ("angular_rate", 1.0),
    "DEG/S": ("angular_rate", 3600.0),
    "°/S": ("angular_rate", 3600.0),
    "RAD/S": ("angular_rate", RAD * 3600),
    "MRAD/S": ("angular_rate", RAD * 3600 / 1000),
    "G": ("acceleration", G0),
    "M/S2": ("acceleration", 1.0),
    "M/S^2": ("acceleration", 1.0),
    "M/S²": ("acceleration", 1.0),
    "NT": ("magnetic_field", 1.0),
    "UT": ("magnetic_field", 1e3),
    "μT": ("magnetic_field", 1e3),
    "TESLA": ("magnetic_field", 1e9),
    "GAUSS": ("magnetic_field", 1e-4 * 1e9),  # 1 G = 1e-4 T
    "S": ("time", 1.0),
    "SEC": ("time", 1.0),
    "MS": ("time", 1e-3),
    "MIN": ("time", 60.0),
    "H": ("time", 3600.0),
    "HR": ("time", 3600.0),
    "DEGC": ("temperature", 1.0),
    "°C": ("temperature", 1.0),
    "CELSIUS": ("temperature", 1.0),
}


def test_every_alias_is_checked() -> None:
    assert {"".join(k.split()).casefold() for k in EXPECTED} == set(ALIASES)


@pytest.mark.parametrize(("unit", "expected"), EXPECTED.items())
def test_alias_factor(unit: str, expected: tuple[str, float]) -> None:
    quantity, factor = expected
    assert conversion_factor(unit, quantity) == pytest.approx(factor, rel=1e-15)


def test_exact_factors() -> None:
    assert conversion_factor("ft", "length") == 0.3048
    assert conversion_factor("usft", "length") == 1200 / 3937
    assert conversion_factor("rad", "angle") == 180 / math.pi
    assert conversion_factor("g", "acceleration") == 9.80665
    assert conversion_factor("deg", "angle") == 1.0


def test_micro_sign_and_greek_mu() -> None:
    assert conversion_factor("\u00b5T", "magnetic_field") == 1000.0
    assert conversion_factor("\u03bcT", "magnetic_field") == 1000.0


def test_canonical_units() -> None:
    assert {q: canonical_unit(q) for q in QUANTITIES} == {
        "length": "m",
        "angle": "deg",
        "angular_rate": "deg/h",
        "acceleration": "m/s2",
        "magnetic_field": "nT",
        "time": "s",
        "dogleg_severity": "deg/30m",
        "temperature": "degC",
        "area": "m2",
    }
    for quantity in QUANTITIES:
        assert conversion_factor(canonical_unit(quantity), quantity) == 1.0


def test_unknown_quantity_is_a_programming_error() -> None:
    with pytest.raises(ValueError, match="unknown quantity 'speed'"):
        canonical_unit("speed")


@pytest.mark.parametrize("unit", ["furlong", "GRAD", "T", "km", "", "m/s", "deg/100m"])
def test_unknown_unit_is_refused(unit: str) -> None:
    with pytest.raises(UnitError, match="unknown unit") as info:
        conversion_factor(unit, "length")
    assert "accepted spellings: " in str(info.value)
    assert "ft" in str(info.value)


@pytest.mark.parametrize(
    ("unit", "quantity", "message"),
    [
        ("ft", "angle", "unit 'ft' is a length, expected an angle"),
        ("deg", "length", "unit 'deg' is an angle, expected a length"),
        ("DEG/100FT", "angular_rate", "is a dogleg severity, expected an angular rate"),
        ("rad/s", "time", "is an angular rate, expected a time"),
        ("min", "angle", "is a time, expected an angle"),
        ("gauss", "acceleration", "is a magnetic field, expected an acceleration"),
        ("G", "magnetic_field", "is an acceleration, expected a magnetic field"),
    ],
)
def test_wrong_dimension_is_refused(unit: str, quantity: str, message: str) -> None:
    with pytest.raises(UnitError, match=message):
        conversion_factor(unit, quantity)


_SPACES = st.text(alphabet=" \t", max_size=3)


@settings(max_examples=200, derandomize=True)
@given(data=st.data(), alias=st.sampled_from(sorted(EXPECTED)))
def test_case_and_whitespace_variants(data: st.DataObject, alias: str) -> None:
    cased = "".join(c.lower() if data.draw(st.booleans()) else c for c in alias)
    spaced = "".join(data.draw(_SPACES) + c for c in cased) + data.draw(_SPACES)
    quantity = EXPECTED[alias][0]
    assert conversion_factor(spaced, quantity) == conversion_factor(alias, quantity)
