"""Normal gravity of the WGS84 ellipsoid (through boule: closed form, valid on and above
the ellipsoid, no free-air correction needed)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

STANDARD_GRAVITY = 9.80665
"""g₀, m/s² (the unit ``g`` of accelerometer specifications)."""


def normal_gravity(latitude_deg: ArrayLike, height_m: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Magnitude of WGS84 normal gravity, m/s², at geodetic latitude (deg) and ellipsoidal
    height (m, ≥ 0; heights below the ellipsoid are clipped to 0, where the closed form
    stops being valid — the difference is < 0.1 mGal per metre of clipping)."""
    import boule  # imported on use: it costs ~0.4 s

    lat = np.asarray(latitude_deg, dtype=float)
    h = np.clip(np.asarray(height_m, dtype=float), 0.0, None)
    value = boule.WGS84.normal_gravity((np.zeros_like(lat), lat, h), si_units=True)
    return np.asarray(value, dtype=float)
