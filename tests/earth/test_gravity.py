"""WGS84 normal gravity against the published constants and formulas (NIMA TR8350.2, 3rd ed.,
§4: equatorial/polar normal gravity, Somigliana's closed form, eq. 4-1, and the height
expansion, eq. 4-3)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike

from pipeline.earth.frames import FloatArray
from pipeline.earth.gravity import STANDARD_GRAVITY, normal_gravity

GAMMA_E = 9.7803253359  # m/s², normal gravity at the equator (TR8350.2 Table 3.4)
GAMMA_P = 9.8321849379  # m/s², at the poles
K = 0.00193185265241  # Somigliana's constant, (b γp)/(a γe) − 1
E2 = 6.69437999014e-3  # first eccentricity squared
A = 6378137.0  # semi-major axis, m
F = 1.0 / 298.257223563  # flattening
M = 0.00344978650684  # ω²a²b/GM


def somigliana(lat_deg: ArrayLike) -> FloatArray:
    s2 = np.sin(np.radians(lat_deg)) ** 2
    gamma: FloatArray = GAMMA_E * (1.0 + K * s2) / np.sqrt(1.0 - E2 * s2)
    return gamma


def test_equator_and_poles_are_the_published_values() -> None:
    assert float(normal_gravity(0.0)) == pytest.approx(GAMMA_E, abs=1e-10)
    assert float(normal_gravity(90.0)) == pytest.approx(GAMMA_P, abs=1e-10)
    assert float(normal_gravity(-90.0)) == pytest.approx(GAMMA_P, abs=1e-10)


def test_somigliana_closed_form_on_the_ellipsoid() -> None:
    lat = np.array([-75.0, -30.0, 10.0, 30.0, 45.0, 61.25, 80.0])
    np.testing.assert_allclose(normal_gravity(lat), somigliana(lat), rtol=0, atol=1e-10)


def test_symmetric_about_the_equator_and_increasing_poleward() -> None:
    lat = np.linspace(0.0, 90.0, 91)
    g = normal_gravity(lat)
    np.testing.assert_allclose(normal_gravity(-lat), g, rtol=0, atol=1e-12)
    assert np.all(np.diff(g) > 0.0)


@pytest.mark.parametrize("h", [1.0, 100.0, 1000.0, 10_000.0])
@pytest.mark.parametrize("lat", [0.0, 33.0, 61.25, 90.0])
def test_height_expansion(lat: float, h: float) -> None:
    """TR8350.2 eq. 4-3: γ_h = γ [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h²/a²]. The expansion
    drops O(f²) terms (~3e-5 of the gradient, 1e-10 m/s² per metre): the closed form agrees
    to that."""
    s2 = np.sin(np.radians(lat)) ** 2
    gamma = somigliana(np.array(lat))
    expected = gamma * (1.0 - 2.0 / A * (1.0 + F + M - 2.0 * F * s2) * h + 3.0 * h**2 / A**2)
    assert float(normal_gravity(lat, h)) == pytest.approx(float(expected), abs=1.5e-10 * h)


@pytest.mark.parametrize("lat", [0.0, 45.0, 61.25, 90.0])
def test_free_air_gradient_near_the_surface(lat: float) -> None:
    """≈ −0.3086 mGal/m (1 mGal = 1e-5 m/s²), slightly weaker toward the poles: eq. 4-3's
    linear term, −0.3087691 + 0.0004398 sin²φ mGal/m, to its O(f²) accuracy."""
    gradient_mgal_per_m = float(normal_gravity(lat, 1.0) - normal_gravity(lat, 0.0)) / 1e-5
    assert gradient_mgal_per_m == pytest.approx(-0.3086, abs=0.0003)
    s2 = np.sin(np.radians(lat)) ** 2
    assert gradient_mgal_per_m == pytest.approx(-0.3087691 + 0.0004398 * s2, abs=2e-5)


def test_heights_below_the_ellipsoid_are_clipped_to_it() -> None:
    assert float(normal_gravity(45.0, -500.0)) == float(normal_gravity(45.0, 0.0))


def test_broadcasting() -> None:
    g = normal_gravity(np.array([[0.0], [61.25]]), np.array([0.0, 100.0, 1000.0]))
    assert g.shape == (2, 3)
    assert g[1, 2] == pytest.approx(float(normal_gravity(61.25, 1000.0)), abs=1e-14)


def test_gravity_at_61n_is_not_one_g() -> None:
    """ENGINEERING.md: at 61.25° N normal gravity is ≈ 1.0014 g₀ (assuming 1 g is a 1.4 mg
    bias)."""
    assert float(normal_gravity(61.25)) / STANDARD_GRAVITY == pytest.approx(1.0014, abs=5e-5)


def test_equal_to_boule_on_and_above_the_ellipsoid() -> None:
    """The closed form is boule's (an independent implementation of Li and Götze 2001):
    equal to 1e-11 m/s² from pole to pole and from the ellipsoid to 9 km."""
    boule = pytest.importorskip("boule")
    lat, h = np.meshgrid(np.linspace(-90.0, 90.0, 181), [0.0, 0.5, 54.3, 1500.0, 9000.0])
    expected = boule.WGS84.normal_gravity((None, lat, h), si_units=True)
    np.testing.assert_allclose(normal_gravity(lat, h), expected, rtol=0, atol=1e-11)
