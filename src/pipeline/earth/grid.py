"""Grid north: meridian (grid) convergence of map projections, through pyproj (PROJ).

Sign convention: the convergence γ is the angle from true north to grid north, positive when
grid north lies east (clockwise) of true north — the bearing of grid north, as GeographicLib
and PROJ's ``meridian_convergence`` define it. Hence

    grid azimuth = true azimuth − γ        true azimuth = grid azimuth + γ

For UTM γ ≈ atan(tan(λ − λ₀)·sin φ): positive east of the central meridian in the northern
hemisphere. pyproj costs ~0.2 s to import, so it is imported on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from pipeline.earth.frames import FloatArray
from pipeline.errors import GyropipeError

if TYPE_CHECKING:
    from pyproj import CRS


class GridError(GyropipeError, ValueError):
    """Unknown or unsuitable CRS, or coordinates outside what it can project."""


def grid_convergence(
    latitude_deg: ArrayLike, longitude_deg: ArrayLike, crs: str | int
) -> float | FloatArray:
    """Meridian convergence γ (deg) of the projected ``crs`` at geographic points.

    ``crs``: anything pyproj reads ("EPSG:32643", 32643, a PROJ string or WKT); a compound CRS
    uses its horizontal part. Latitude and longitude (deg) are on the CRS's own geodetic
    datum (for γ, the metre-level shift between WGS84 and other modern datums is negligible).
    γ is the angle from true north to grid north, clockwise positive:
    ``grid azimuth = true azimuth − γ``. Scalars in, float out; arrays broadcast.
    """
    from pyproj import Proj  # imported on use: ~0.2 s
    from pyproj.exceptions import ProjError

    horizontal = _projected_crs(crs)
    try:
        lat, lon = np.broadcast_arrays(
            np.asarray(latitude_deg, dtype=float), np.asarray(longitude_deg, dtype=float)
        )
    except (TypeError, ValueError) as exc:
        raise GridError(f"latitude and longitude must be numeric and broadcast: {exc}") from None
    bad = ~np.isfinite(lat) | ~np.isfinite(lon) | (np.abs(lat) > 90.0)
    if bad.any():
        i = np.unravel_index(int(np.argmax(bad)), bad.shape)
        raise GridError(
            f"coordinates must be finite with latitude within [-90, 90] deg; "
            f"got latitude {lat[i]}, longitude {lon[i]}"
        )
    if lat.size == 0:
        return np.zeros(lat.shape)
    try:
        factors = Proj(horizontal).get_factors(lon.ravel(), lat.ravel(), errcheck=True)
    except ProjError as exc:
        raise GridError(f"cannot compute the convergence of {crs!r} here: {exc}") from None
    gamma = np.asarray(factors.meridian_convergence, dtype=float).reshape(lat.shape)
    if not np.isfinite(gamma).all():
        i = np.unravel_index(int(np.argmax(~np.isfinite(gamma))), gamma.shape)
        raise GridError(
            f"{crs!r} cannot project latitude {lat[i]}, longitude {lon[i]} (no convergence)"
        )
    return float(gamma) if gamma.ndim == 0 else gamma


def utm_crs(latitude: float, longitude: float) -> str:
    """The WGS84 UTM CRS of the standard zone at a point: ``EPSG:326zz`` (north, latitude
    ≥ 0) or ``EPSG:327zz`` (south), with the Norway (32V) and Svalbard (31X–37X) exceptions.
    UTM covers 80° S to 84° N; beyond it raises :class:`GridError` (use UPS: EPSG:32661 north,
    EPSG:32761 south)."""
    lat, lon = float(latitude), float(longitude)
    if not (np.isfinite(lat) and np.isfinite(lon)):
        raise GridError(f"coordinates must be finite; got {lat}, {lon}")
    if not -80.0 <= lat <= 84.0:
        raise GridError(
            f"latitude {lat} is outside UTM (80° S to 84° N); "
            "use UPS: EPSG:32661 (north) or EPSG:32761 (south)"
        )
    lon = (lon + 180.0) % 360.0 - 180.0
    zone = int((lon + 180.0) // 6.0) + 1
    if 56.0 <= lat < 64.0 and 3.0 <= lon < 12.0:
        zone = 32
    elif lat >= 72.0 and 0.0 <= lon < 42.0:
        zone = 31 if lon < 9.0 else 33 if lon < 21.0 else 35 if lon < 33.0 else 37
    return f"EPSG:{32600 + zone if lat >= 0.0 else 32700 + zone}"


def _projected_crs(crs: str | int) -> CRS:
    """The pyproj CRS of ``crs`` (horizontal part of a compound one); it must be projected."""
    import pyproj
    from pyproj.exceptions import CRSError

    if isinstance(crs, bool):
        raise GridError(f"not a CRS: {crs!r}")
    try:
        parsed = pyproj.CRS.from_user_input(f"EPSG:{crs}" if isinstance(crs, int) else crs)
    except CRSError as exc:
        raise GridError(f"unknown CRS {crs!r}: {exc}") from None
    if parsed.is_compound:
        parsed = parsed.sub_crs_list[0]
    if not parsed.is_projected:
        raise GridError(f"CRS {crs!r} ({parsed.name}) is not a projected CRS: it has no grid north")
    return parsed
