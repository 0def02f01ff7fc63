"""Normal gravity of the WGS84 ellipsoid: the closed form of Li and Götze (2001, Geophysics
66(6), 1660–1668; Lakshmanan 1991 corrected), in ellipsoidal-harmonic coordinates
(Hofmann-Wellenhof and Moritz 2006, §2.7–2.8). Valid on and above the ellipsoid, with no
free-air correction needed. NumPy alone (no geodesy library is imported for it)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

STANDARD_GRAVITY = 9.80665
"""g₀, m/s² (the unit ``g`` of accelerometer specifications)."""

WGS84_A = 6378137.0
"""Semimajor axis, m."""
WGS84_F = 1.0 / 298.257223563
"""Flattening."""
WGS84_GM = 3.986004418e14
"""Geocentric gravitational constant, m³/s²."""
WGS84_OMEGA = 7.292115e-5
"""Angular velocity, rad/s."""
METHOD = "WGS84 normal gravity, closed form of Li and Götze (2001)"
"""How :func:`normal_gravity` is computed, as a report cites it."""


def normal_gravity(latitude_deg: ArrayLike, height_m: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Magnitude of WGS84 normal gravity, m/s², at geodetic latitude (deg) and ellipsoidal
    height (m, ≥ 0; heights below the ellipsoid are clipped to 0, where the closed form
    stops being valid — the difference is < 0.1 mGal per metre of clipping)."""
    lat = np.radians(np.asarray(latitude_deg, dtype=float))
    h = np.clip(np.asarray(height_m, dtype=float), 0.0, None)
    a, b = WGS84_A, WGS84_A * (1.0 - WGS84_F)
    e2 = a * a - b * b  # linear eccentricity squared
    e = np.sqrt(e2)
    sinlat = np.sin(lat)
    coslat = np.sqrt(1.0 - sinlat**2)
    # geodetic → ellipsoidal-harmonic (reduced latitude β, u: the confocal semiminor axis)
    beta = np.arctan2(b * sinlat, a * coslat)
    z2 = (b * np.sin(beta) + h * sinlat) ** 2
    r2 = (a * np.sqrt(1.0 - np.sin(beta) ** 2) + h * coslat) ** 2
    big_d, big_r = (r2 - z2) / e2, (r2 + z2) / e2
    cosbeta2 = 0.5 + big_r / 2 - np.sqrt(0.25 + big_r**2 / 4 - big_d / 2)
    u = np.sqrt(r2 + z2 - e2 * cosbeta2)
    sinbeta2 = 1.0 - cosbeta2
    q0 = 0.5 * ((1 + 3 * (b / e) ** 2) * np.arctan2(e, b) - 3 * b / e)
    qp = 3 * (1 + (u / e) ** 2) * (1 - u / e * np.arctan2(e, u)) - 1
    w = np.sqrt((u**2 + e2 * sinbeta2) / (u**2 + e2))
    gm_term = WGS84_GM / (u**2 + e2)
    spin = (0.5 * sinbeta2 - 1 / 6) * (a**2 * e * qp * WGS84_OMEGA**2 / ((u**2 + e2) * q0))
    centrifugal = -cosbeta2 * u * WGS84_OMEGA**2
    return np.asarray((gm_term + spin + centrifugal) / w, dtype=float)
