"""Unit normalisation: oilfield unit spellings → conversion factors to canonical units.

Unit strings in survey files are free text (``F``, ``FEET``, ``DEGA``, ``°/100'``…). They are
looked up in :data:`ALIASES`, an explicit table of spellings, compared case-insensitively
with all whitespace removed. A spelling not in the table is refused, never guessed: pint
alone would read ``F`` as farad, ``G`` as gram and ``T`` as tonne. Ambiguous spellings
(``GRAD``: gradian or gradient?) are deliberately absent.

Factors come from pint, with one :class:`pint.UnitRegistry` created on first use (importing
this module stays cheap). The registry works in exact fractions, so each factor is rounded
to float once: ``ft`` → ``m`` is exactly ``0.3048``.
"""

from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass
from fractions import Fraction
from functools import cache
from typing import Any

from pipeline.errors import UnitError

ALIASES: dict[str, str] = {
    # length
    "m": "meter",
    "meter": "meter",
    "meters": "meter",
    "metre": "meter",
    "metres": "meter",
    "f": "foot",
    "ft": "foot",
    "feet": "foot",
    "foot": "foot",
    "usft": "survey_foot",  # US survey foot, 1200/3937 m
    "us-ft": "survey_foot",
    "ftus": "survey_foot",  # the Energistics symbol (WITSML, RESQML exports)
    "in": "inch",  # hole and casing sizes
    "inch": "inch",
    "inches": "inch",
    # area: position variances and covariances
    "m2": "meter ** 2",
    "m^2": "meter ** 2",
    "m²": "meter ** 2",
    "ft2": "foot ** 2",
    "ft^2": "foot ** 2",
    "ft²": "foot ** 2",
    # angle
    "deg": "degree",
    "dega": "degree",
    "degree": "degree",
    "degrees": "degree",
    "°": "degree",
    "rad": "radian",
    "radian": "radian",
    "radians": "radian",
    # dogleg severity
    "°/100'": "degree / (100 * foot)",
    "°/100ft": "degree / (100 * foot)",
    "deg/100'": "degree / (100 * foot)",
    "deg/100ft": "degree / (100 * foot)",
    "°/30m": "degree / (30 * meter)",
    "deg/30m": "degree / (30 * meter)",
    # angular rate
    "deg/h": "degree / hour",
    "deg/hr": "degree / hour",
    "°/h": "degree / hour",
    "°/hr": "degree / hour",
    "deg/s": "degree / second",
    "°/s": "degree / second",
    "rad/s": "radian / second",
    "mrad/s": "milliradian / second",
    # acceleration
    "g": "standard_gravity",  # 9.80665 m/s², never gram
    "m/s2": "meter / second ** 2",
    "m/s^2": "meter / second ** 2",
    "m/s²": "meter / second ** 2",
    # magnetic field
    "nt": "nanotesla",
    "ut": "microtesla",
    "μt": "microtesla",  # also matches the micro sign µ (casefolded to μ)
    "tesla": "tesla",
    "gauss": "tesla / 10000",  # pint's gauss is CGS-Gaussian; fix it to 1e-4 T
    # time
    "s": "second",
    "sec": "second",
    "ms": "millisecond",
    "min": "minute",
    "h": "hour",
    "hr": "hour",
    # temperature: Celsius alone — °F and K are offset from it, which no factor converts
    # (and "F" is a foot here)
    "degc": "delta_degree_Celsius",
    "°c": "delta_degree_Celsius",
    "celsius": "delta_degree_Celsius",
}
"""Accepted unit spellings (lower case, no whitespace) → pint expression."""


@dataclass(frozen=True)
class Quantity:
    """A physical quantity: its canonical unit and how messages name it."""

    canonical: str
    label: str


QUANTITIES: dict[str, Quantity] = {
    "length": Quantity("m", "a length"),
    "angle": Quantity("deg", "an angle"),
    "angular_rate": Quantity("deg/h", "an angular rate"),
    "acceleration": Quantity("m/s2", "an acceleration"),
    "magnetic_field": Quantity("nT", "a magnetic field"),
    "time": Quantity("s", "a time"),
    "dogleg_severity": Quantity("deg/30m", "a dogleg severity"),
    "temperature": Quantity("degC", "a temperature"),
    "area": Quantity("m2", "an area (a position variance)"),
}
"""Quantity name → canonical unit. Every canonical unit is itself a spelling in ALIASES."""


def canonical_unit(quantity: str) -> str:
    """Canonical unit of ``quantity`` (``"length"`` → ``"m"``, ``"angle"`` → ``"deg"``…).

    Raises ``ValueError`` for a quantity name not in :data:`QUANTITIES` (a programming error).
    """
    return _quantity(quantity).canonical


def conversion_factor(unit: str, quantity: str) -> float:
    """Multiplier taking values in ``unit`` to the canonical unit of ``quantity``.

    ``conversion_factor("ft", "length")`` is ``0.3048`` (ft → m). Raises
    :class:`~pipeline.errors.UnitError` when ``unit`` is not an accepted spelling or is not
    a unit of ``quantity``.
    """
    target = _quantity(quantity)
    entry = _table().get(_key(unit))
    if entry is None:
        raise UnitError(
            f"unknown unit {unit!r}, expected {target.label}; accepted spellings: "
            + ", ".join(spelled for spelled, (q, _) in _table().items() if q == quantity)
        )
    found, factor = entry
    if found != quantity:
        raise UnitError(
            f"unit {unit!r} is {QUANTITIES[found].label}, expected {target.label} "
            f"(canonical unit {target.canonical!r})"
        )
    return factor


def is_unit_of(unit: str, quantity: str) -> bool:
    """True if ``unit`` is an accepted spelling of a unit of ``quantity``."""
    entry = _table().get(_key(unit))
    return entry is not None and entry[0] == quantity


def quantity_of(unit: str) -> str | None:
    """The quantity ``unit`` is an accepted spelling of (``"ft"`` → ``"length"``); None if
    it is none."""
    entry = _table().get(_key(unit))
    return None if entry is None else entry[0]


def _key(unit: str) -> str:
    return "".join(unit.split()).casefold()


def _quantity(name: str) -> Quantity:
    try:
        return QUANTITIES[name]
    except KeyError:
        raise ValueError(f"unknown quantity {name!r}; known: {', '.join(QUANTITIES)}") from None


@cache
def _table() -> dict[str, tuple[str, float]]:
    """Each spelling → (its quantity, factor to that quantity's canonical unit)."""
    pint = _import_pint()

    ureg: Any = pint.UnitRegistry(non_int_type=Fraction)  # exact arithmetic, one rounding
    canonical = {name: ureg.Quantity(ALIASES[_key(q.canonical)]) for name, q in QUANTITIES.items()}
    table: dict[str, tuple[str, float]] = {}
    for spelling, expression in ALIASES.items():
        source = ureg.Quantity(expression)
        for name, target in canonical.items():
            if source.dimensionality == target.dimensionality:
                ratio = (source / target).to("dimensionless").magnitude
                table[spelling] = (name, float(Fraction(ratio)))
                break
        else:
            raise AssertionError(f"unit alias {spelling!r} measures none of {list(QUANTITIES)}")
    return table


def _import_pint() -> Any:
    """pint, kept from importing dask: pint probes for dask at import and loads it (half a
    second) whenever it is installed; gyropipe never hands pint a dask array."""
    if "pint" in sys.modules or "dask" in sys.modules:
        return importlib.import_module("pint")
    sys.modules["dask"] = None  # type: ignore[assignment]  # find_spec("dask") → None
    try:
        return importlib.import_module("pint")
    finally:
        del sys.modules["dask"]
