"""Grid convergence: published values (GeographicLib GeoConvert), the UTM closed form, and the
sign convention checked geometrically (grid azimuth = true azimuth − γ)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike
from pyproj import CRS, Transformer

from pipeline.earth.frames import FloatArray
from pipeline.earth.grid import GridError, grid_convergence, utm_crs
from pipeline.errors import GyropipeError

# GeographicLib `GeoConvert -u -s -p 9 -c` (meridian convergence = bearing of grid north,
# clockwise from true north, deg), as recorded in clickr/SwiftGeographicLib
# Tests/UTMUPSTests/UTMTests.swift.
GEOCONVERT = [
    (-31.93980, 115.96650, "EPSG:32750", 0.5467937033262),  # Perth airport, zone 50S
    (47.6514, 106.8216, "EPSG:32648", 1.3464793685012),  # Ulaanbaatar, zone 48N
    (33.30000003988349, 44.39999994689769, "EPSG:32638", -0.3294222515151),  # zone 38N
]


@pytest.mark.parametrize(("lat", "lon", "crs", "gamma"), GEOCONVERT)
def test_geographiclib_published_values(lat: float, lon: float, crs: str, gamma: float) -> None:
    assert grid_convergence(lat, lon, crs) == pytest.approx(gamma, abs=1e-9)


def closed_form(lat: ArrayLike, lon: ArrayLike, central_meridian: float) -> FloatArray:
    """Spherical UTM convergence atan(tan(λ − λ₀)·sin φ), deg."""
    dlon = np.radians(np.asarray(lon, dtype=float) - central_meridian)
    gamma: FloatArray = np.degrees(np.arctan(np.tan(dlon) * np.sin(np.radians(lat))))
    return gamma


def test_utm_matches_the_closed_form() -> None:
    rng = np.random.default_rng(11)
    lat = rng.uniform(-80.0, 84.0, 500)
    lon_near = 75.0 + rng.uniform(-1.0, 1.0, 500)
    near = grid_convergence(lat, lon_near, "EPSG:32643")
    np.testing.assert_allclose(near, closed_form(lat, lon_near, 75.0), rtol=0, atol=1e-6)
    lon_far = 75.0 + rng.uniform(-3.5, 3.5, 500)
    far = grid_convergence(lat, lon_far, "EPSG:32643")
    np.testing.assert_allclose(far, closed_form(lat, lon_far, 75.0), rtol=0, atol=1e-3)


def test_closed_form_near_the_central_meridian_to_a_microdegree() -> None:
    lat = np.linspace(-75.0, 80.0, 32)
    lon = 75.0 + np.linspace(-0.5, 0.5, 32)
    gamma = grid_convergence(lat, lon, 32643)
    np.testing.assert_allclose(gamma, closed_form(lat, lon, 75.0), rtol=0, atol=1e-6)


@pytest.mark.parametrize(
    ("crs", "lat", "lon"),
    [
        ("EPSG:32643", 61.25, 73.4),  # UTM 43N
        ("EPSG:32750", -31.9, 118.9),  # UTM 50S, east of the central meridian
        ("EPSG:2056", 46.5, 9.8),  # Swiss oblique Mercator on the Bessel ellipsoid
        ("EPSG:3413", 78.0, 15.0),  # polar stereographic north
    ],
)
@pytest.mark.parametrize("azimuth", [0.0, 37.0, 90.0, 200.0, 315.0])
def test_sign_convention_grid_azimuth_is_true_azimuth_minus_convergence(
    crs: str, lat: float, lon: float, azimuth: float
) -> None:
    """Walk 10 m along a true azimuth on the CRS's own ellipsoid, project both ends: the grid
    bearing of the step is the true azimuth minus γ (conformal projections keep angles)."""
    projected = CRS(crs)
    geodetic = projected.geodetic_crs
    assert geodetic is not None
    lon2, lat2, _ = geodetic.get_geod().fwd(lon, lat, azimuth, 10.0)  # type: ignore[union-attr]
    to_grid = Transformer.from_crs(geodetic, projected, always_xy=True)
    (x1, x2), (y1, y2) = to_grid.transform([lon, lon2], [lat, lat2])
    grid_azimuth = np.degrees(np.arctan2(x2 - x1, y2 - y1))
    gamma = grid_convergence(lat, lon, crs)
    difference = (grid_azimuth - (azimuth - gamma) + 180.0) % 360.0 - 180.0
    assert abs(difference) < 1e-5


def test_sign_of_utm_convergence() -> None:
    """Northern hemisphere: positive east of the central meridian, negative west of it;
    reversed in the southern hemisphere; zero on the central meridian and the equator."""
    assert grid_convergence(61.25, 76.0, 32643) > 0.0
    assert grid_convergence(61.25, 74.0, 32643) < 0.0
    assert grid_convergence(-61.25, 76.0, 32743) < 0.0
    assert grid_convergence(61.25, 75.0, 32643) == pytest.approx(0.0, abs=1e-12)
    assert grid_convergence(0.0, 73.0, 32643) == pytest.approx(0.0, abs=1e-12)


def test_shapes() -> None:
    scalar = grid_convergence(61.25, 73.4, "EPSG:32643")
    assert isinstance(scalar, float)
    grid = grid_convergence(np.array([[61.0], [62.0]]), np.array([73.0, 74.0, 75.0]), 32643)
    assert isinstance(grid, np.ndarray) and grid.shape == (2, 3)
    assert grid[1, 0] == pytest.approx(grid_convergence(62.0, 73.0, 32643), abs=1e-12)
    empty = grid_convergence(np.zeros(0), np.zeros(0), 32643)
    assert isinstance(empty, np.ndarray) and empty.shape == (0,)


def test_compound_crs_uses_its_horizontal_part() -> None:
    with_height = grid_convergence(61.25, 73.4, "EPSG:32643+5773")
    assert with_height == grid_convergence(61.25, 73.4, "EPSG:32643")


@pytest.mark.parametrize(
    ("crs", "message"),
    [
        ("EPSG:999999", "unknown CRS 'EPSG:999999'"),
        (999999, "unknown CRS 999999"),
        ("not a crs", "unknown CRS 'not a crs'"),
        ("EPSG:4326", "not a projected CRS"),
        ("EPSG:4978", "not a projected CRS"),
    ],
)
def test_bad_crs_raises(crs: str | int, message: str) -> None:
    with pytest.raises(GridError, match=message) as caught:
        grid_convergence(61.25, 73.4, crs)
    assert isinstance(caught.value, GyropipeError)


@pytest.mark.parametrize(
    ("lat", "lon"), [(91.0, 73.0), (-90.5, 0.0), (np.nan, 73.0), (61.0, np.inf), ("x", 0.0)]
)
def test_bad_coordinates_raise(lat: object, lon: object) -> None:
    with pytest.raises(GridError):
        grid_convergence(lat, lon, 32643)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("lat", "lon", "expected"),
    [
        (61.25, 73.4, "EPSG:32643"),
        (-31.9398, 115.9665, "EPSG:32750"),
        (0.0, 0.5, "EPSG:32631"),
        (-0.1, 0.5, "EPSG:32731"),
        (51.5, -0.1, "EPSG:32630"),
        (60.0, 5.0, "EPSG:32632"),  # Norway exception (31V → 32V)
        (60.0, 2.9, "EPSG:32631"),
        (78.0, 8.0, "EPSG:32631"),  # Svalbard exceptions
        (78.0, 15.0, "EPSG:32633"),
        (78.0, 25.0, "EPSG:32635"),
        (78.0, 40.0, "EPSG:32637"),
        (78.0, 45.0, "EPSG:32638"),
        (30.0, 180.0, "EPSG:32601"),
        (30.0, -180.0, "EPSG:32601"),
        (30.0, 179.9, "EPSG:32660"),
        (30.0, 270.0, "EPSG:32616"),
        (84.0, 10.0, "EPSG:32633"),
        (-80.0, 10.0, "EPSG:32732"),
    ],
)
def test_utm_crs(lat: float, lon: float, expected: str) -> None:
    assert utm_crs(lat, lon) == expected


@pytest.mark.parametrize(("lat", "lon"), [(84.5, 0.0), (-80.5, 0.0), (np.nan, 0.0)])
def test_utm_crs_outside_utm_raises(lat: float, lon: float) -> None:
    with pytest.raises(GridError):
        utm_crs(lat, lon)


def test_utm_crs_zone_has_the_point_near_its_central_meridian() -> None:
    rng = np.random.default_rng(5)
    for lat, lon in zip(rng.uniform(-80.0, 56.0, 50), rng.uniform(-180.0, 180.0, 50), strict=True):
        gamma = grid_convergence(lat, lon, utm_crs(lat, lon))
        assert isinstance(gamma, float)
        assert abs(gamma) <= abs(float(closed_form(lat, 3.0, 0.0))) + 1e-9


def test_crs_in_feet_gives_the_same_convergence_as_in_metres() -> None:
    """Regression guard for PROJ issue 3824 (proj_factors wrong for CRSs in feet)."""
    feet = grid_convergence(33.5, -110.5, "EPSG:2222")  # NAD83 / Arizona East (ft)
    metres = grid_convergence(33.5, -110.5, "EPSG:26948")  # NAD83 / Arizona East
    assert feet == pytest.approx(metres, abs=1e-12)
    assert metres == pytest.approx(float(closed_form(33.5, -110.5, -110.0 - 10.0 / 60.0)), abs=1e-3)
