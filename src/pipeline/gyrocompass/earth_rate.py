"""The Earth rate a station's gyro fit found, checked against the Earth's (DOMAIN.md §3).

The horizontal component Ω cos φ and, when the axial gyro joins the fit, the vertical
Ω sin φ must be within a relative tolerance and 4 σ of the fitted value. A station outside is
rejected, never solved: gyro rates in the wrong unit (rad/s or deg/s read as °/h), a dead or
mis-scaled gyro or a wrong latitude would otherwise give a confident, wrong azimuth (a rad/s
record compasses to ≈ 180°, σ 1e-5°). Rates in °/h, angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.precision import OMEGA_DEG_H

EARTH_RATE_SIGMAS = 4.0
"""Multiples of the fitted Earth rate's σ added (in quadrature) to the relative tolerance."""
RATE_UNITS = {
    "rad/s": np.radians(1.0) / 3600.0,
    "deg/s": 1.0 / 3600.0,
    "mrad/s": np.radians(1.0) / 3.6,
}
"""What 1 °/h reads as in other rate units: the ratio of fitted to expected Earth rate that a
record in that unit, taken for °/h, shows (a factor 17 or more apart from each other)."""
LOOKS_LIKE = 2.0
"""A ratio within this factor of a unit's (:data:`RATE_UNITS`) names the unit in the hint."""


@dataclass(frozen=True)
class EarthRate:
    """One component of the Earth rate a station's gyro fit found, against the Earth's."""

    component: str
    """``horizontal`` or ``vertical``"""
    fitted: float
    """°/h"""
    expected: float
    """°/h (the vertical is positive up: Ω sin φ)"""
    limit: float
    """largest allowed |fitted − expected|, °/h"""

    @property
    def ok(self) -> bool:
        return bool(abs(self.fitted - self.expected) <= self.limit)

    @property
    def ratio(self) -> float:
        return self.fitted / self.expected if self.expected else float("nan")

    def describe(self, latitude: float) -> str:
        """``fitted horizontal Earth rate 0.000035 °/h is 0.0000048× the expected 7.24 °/h
        at 61.25° N``."""
        where = f"{abs(latitude):.2f}° {'N' if latitude >= 0 else 'S'}"
        times = f" is {figures(self.ratio)}×" if self.expected else ","
        return (
            f"fitted {self.component} Earth rate {figures(self.fitted)} °/h{times} the "
            f"expected {self.expected:.2f} °/h at {where}"
        )

    def looks_like(self) -> str:
        """The rate unit whose factor the ratio matches within :data:`LOOKS_LIKE`
        (``they look like rad/s``; the inverse for °/h converted as if in that unit), or ''."""
        if not self.expected or not self.ratio > 0:
            return ""
        for unit, factor in RATE_UNITS.items():
            if abs(np.log(self.ratio / factor)) <= np.log(LOOKS_LIKE):
                return f"they look like {unit}"
            if abs(np.log(self.ratio * factor)) <= np.log(LOOKS_LIKE):
                return f"they look like °/h converted as if they were {unit}"
        return ""


CIRCLE = np.radians(np.arange(0.0, 360.0, 2.0))
"""Directions (rad) searched for the Earth-rate point nearest a fit."""
HINT = "are the gyro rates in °/h?"


def figures(value: float) -> str:
    """Two significant figures without an exponent (``0.000035``, ``7.2``, ``1800``)."""
    if not np.isfinite(value) or value == 0:
        return f"{value:g}"
    return str(np.format_float_positional(value, precision=2, fractional=False, trim="-"))


def failure_hint(checks: list[EarthRate]) -> str:
    """The question to ask, and the unit the failed checks' ratios point to if any."""
    looks = next((c.looks_like() for c in checks if not c.ok and c.looks_like()), "")
    return f"{HINT} ({looks})" if looks else HINT


def earth_rate_reason(checks: list[EarthRate], latitude: float, hint: str = "") -> str:
    """Why a station's Earth rate is implausible: each failed component, then the hint
    (default: the question, with the unit its own ratios point to)."""
    text = "; ".join(c.describe(latitude) for c in checks if not c.ok)
    return f"{text}: {hint or failure_hint(checks)}"


class StationReject(Exception):
    """A station that cannot be solved, and why."""


class EarthRateReject(StationReject):
    """A station whose fitted Earth rate is not the Earth's (:func:`earth_rate_check`)."""

    def __init__(self, message: str, checks: list[EarthRate]) -> None:
        self.checks = checks
        super().__init__(message)


def earth_rate_check(
    obs: FloatArray,
    cov: FloatArray,
    inclination: float,
    latitude: float,
    tolerance: float,
    *,
    near_vertical: bool = False,
) -> list[EarthRate]:
    """The Earth rate a station's fit found, against the Earth's (DOMAIN.md §3), per
    component; latitude and inclination in radians, rates in °/h.

    ``obs`` with covariance ``cov``: inclined, the high-side and right-side components
    (h, r) or, when the axial gyro joins the fit, (h, r, z); near vertical, the transverse
    components (u, v) of the tilt-corrected fit, Ω cos φ times north's. The horizontal
    component, against k = Ω cos φ, is

    - near vertical: √(u² + v²) (low by at most 1 − cos I);
    - from (h, r, z), free of any assumption: √((h cos I + z sin I)² + r²), and the
      vertical h sin I − z cos I against Ω sin φ;
    - from (h, r) alone: √(((h − Ω sin φ sin I)/cos I)² + r²), the vertical share taken
      from the latitude (the azimuth solver does the same); nothing near horizontal, where
      cos I → 0 leaves it undetermined.

    Each component may depart from its expected value by
    ``√((tolerance·expected)² + (4σ)²)``, σ propagated from ``cov`` (first order) — from
    (h, r), where that fails, the larger of it and σ at the Earth-rate point nearest the fit
    (toward horizontal a noisy along near zero leaves the gradient at the fit r's σ alone).
    """
    k = OMEGA_DEG_H * np.cos(latitude)
    up = OMEGA_DEG_H * np.sin(latitude)
    ci, si = np.cos(inclination), np.sin(inclination)
    parts: list[tuple[str, float, FloatArray, float]] = []
    if near_vertical:
        value = float(np.hypot(obs[0], obs[1]))
        parts.append(("horizontal", value, obs[:2] / (value or 1.0), k))
    elif len(obs) == 3:
        h, r, z = obs
        along = h * ci + z * si
        value = float(np.hypot(along, r))
        grad = np.array([along * ci, r, along * si]) / (value or 1.0)
        parts.append(("horizontal", value, grad, k))
        parts.append(("vertical", float(h * si - z * ci), np.array([si, 0.0, -ci]), up))
    elif abs(ci) > 1e-6:
        h, r = obs[:2]
        along = (h - up * si) / ci
        value = float(np.hypot(along, r))
        grad = np.array([along / ci, r]) / (value or 1.0)
        if abs(value - k) > _limit(grad, cov, k, tolerance):
            # near horizontal along's σ grows as 1/cos I: where its noise leaves it near zero
            # the gradient at the fit sees only r's σ; the Earth-rate point nearest the fit
            # sees along's too (the larger σ of the two is taken)
            toward = _nearest_on_circle(np.array([along, r]), cov[:2, :2], ci, k) / [ci, 1.0]
            grad = max(grad, toward, key=lambda g: float(g @ cov[:2, :2] @ g))
        parts.append(("horizontal", value, grad, k))
    return [
        EarthRate(component, value, float(expected), _limit(grad, cov, expected, tolerance))
        for component, value, grad, expected in parts
    ]


def _limit(grad: FloatArray, cov: FloatArray, expected: float, tolerance: float) -> float:
    """The largest allowed |fitted − expected|: the tolerance and 4 σ (first order, ``grad``
    of the fitted value) in quadrature."""
    sigma = float(np.sqrt(grad @ cov[: len(grad), : len(grad)] @ grad))
    return float(np.hypot(tolerance * abs(expected), EARTH_RATE_SIGMAS * sigma))


def _nearest_on_circle(point: FloatArray, cov: FloatArray, ci: float, k: float) -> FloatArray:
    """Unit direction of the point of the circle of radius ``k`` nearest ``point`` (along, r)
    in the metric of (h, r) covariance ``cov`` (along = (h − Ω sin φ sin I)/cos I)."""
    scale = np.array([1.0 / ci, 1.0])
    weight = np.linalg.inv(cov * np.outer(scale, scale))
    unit = np.stack([np.cos(CIRCLE), np.sin(CIRCLE)])
    gap = point[:, None] - k * unit
    best = int(np.argmin(np.einsum("ic,ij,jc->c", gap, weight, gap)))
    out: FloatArray = unit[:, best]
    return out
