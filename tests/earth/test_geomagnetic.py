"""Geomagnetic reference field against published values (WMM2025 report, GeographicLib) and the
identities between its elements."""

from __future__ import annotations

import datetime as dt
import importlib.metadata
import subprocess
import sys

import numpy as np
import pytest

from pipeline.earth.geomagnetic import (
    BLACKOUT_ZONE_NT,
    GeomagneticInputError,
    ModelValidityError,
    decimal_year,
    field_model,
    reference_field,
)
from pipeline.earth.site import MagneticReference, Site
from pipeline.errors import GyropipeError


def at_decimal_year(year: float) -> dt.datetime:
    """The datetime of a decimal year (year + elapsed fraction of that year)."""
    whole = int(year)
    start = dt.datetime(whole, 1, 1)
    length = dt.datetime(whole + 1, 1, 1) - start
    return start + (year - whole) * length


# WMM2025 Technical Report, test values table (NOAA NCEI / BGS, Dec 2024; the same numbers are
# in WMM2025testvalues.pdf / WMM2025_TEST_VALUES.txt): decimal year, height above the WGS84
# ellipsoid (km), geodetic latitude, longitude (deg), then X, Y, Z, H, F (nT, to 0.1 nT) and
# I, D (deg, to 0.01°).
WMM2025_TABLE = [
    (2025.0, 0, 80, 0, 6521.6, 145.9, 54791.5, 6523.2, 55178.5, 83.21, 1.28),
    (2025.0, 0, 0, 120, 39677.8, -109.6, -10580.2, 39677.9, 41064.3, -14.93, -0.16),
    (2025.0, 0, -80, 240, 6117.5, 15751.9, -52022.5, 16898.1, 54698.2, -72.00, 68.78),
    (2025.0, 100, 80, 0, 6216.0, 92.4, 52598.8, 6216.7, 52964.9, 83.26, 0.85),
    (2025.0, 100, 0, 120, 37688.6, -96.2, -10152.1, 37688.7, 39032.1, -15.08, -0.15),
    (2025.0, 100, -80, 240, 5907.6, 14780.3, -49540.7, 15917.1, 52035.0, -72.19, 68.21),
    (2027.5, 0, 80, 0, 6500.8, 294.5, 54869.4, 6507.5, 55253.9, 83.24, 2.59),
    (2027.5, 0, 0, 120, 39701.6, -167.4, -10381.8, 39702.0, 41036.9, -14.65, -0.24),
    (2027.5, 0, -80, 240, 6200.7, 15730.3, -51783.7, 16908.3, 54474.2, -71.92, 68.49),
    (2027.5, 100, 80, 0, 6196.7, 233.8, 52670.5, 6201.1, 53034.3, 83.29, 2.16),
    (2027.5, 100, 0, 120, 37711.5, -148.7, -9969.8, 37711.8, 39007.4, -14.81, -0.23),
    (2027.5, 100, -80, 240, 5984.0, 14760.1, -49317.7, 15927.0, 51825.7, -72.10, 67.93),
]
NT_PRINTED = 0.05 + 1e-9  # half the last printed digit
DEG_PRINTED = 0.005 + 1e-9


def test_wmm2025_matches_the_report_test_values_vectorised() -> None:
    rows = np.array(WMM2025_TABLE)
    dates = [at_decimal_year(y) for y in rows[:, 0]]
    field = reference_field(rows[:, 2], rows[:, 3], rows[:, 1] * 1000.0, dates)
    computed = [
        field.north,
        field.east,
        field.down,
        field.horizontal,
        field.total_field,
        field.dip,
        field.declination,
    ]
    for column, (values, tol) in enumerate(
        zip(computed, [NT_PRINTED] * 5 + [DEG_PRINTED] * 2, strict=True)
    ):
        np.testing.assert_allclose(values, rows[:, 4 + column], rtol=0, atol=tol)


@pytest.mark.parametrize("row", WMM2025_TABLE, ids=lambda r: f"{r[0]}-{r[1]}km-{r[2]}-{r[3]}")
def test_wmm2025_report_values_point_by_point(row: tuple[float, ...]) -> None:
    year, h_km, lat, lon, x, y, z, h, f, inc, dec = row
    field = reference_field(lat, lon, h_km * 1000.0, at_decimal_year(year))
    assert field.north.shape == ()
    assert float(field.north) == pytest.approx(x, abs=NT_PRINTED)
    assert float(field.east) == pytest.approx(y, abs=NT_PRINTED)
    assert float(field.down) == pytest.approx(z, abs=NT_PRINTED)
    assert float(field.horizontal) == pytest.approx(h, abs=NT_PRINTED)
    assert float(field.total_field) == pytest.approx(f, abs=NT_PRINTED)
    assert float(field.dip) == pytest.approx(inc, abs=DEG_PRINTED)
    assert float(field.declination) == pytest.approx(dec, abs=DEG_PRINTED)


def test_wmm2025_report_numerical_example_to_ten_decimals() -> None:
    """WMM2025 Technical Report numerical example (2027.5, 100 km, 80° S, 240° E), printed to
    1e-10: checks the km/m, geodetic/geocentric and decimal-year handling far below 0.1 nT."""
    field = reference_field(-80.0, 240.0, 100_000.0, dt.datetime(2027, 7, 2, 12))
    assert float(field.north) == pytest.approx(5983.9760496518, abs=1e-6)
    assert float(field.east) == pytest.approx(14760.1359757868, abs=1e-6)
    assert float(field.down) == pytest.approx(-49317.6706154255, abs=1e-6)
    assert float(field.horizontal) == pytest.approx(15927.0079860130, abs=1e-6)
    assert float(field.total_field) == pytest.approx(51825.6907172314, abs=1e-6)
    assert np.radians(float(field.declination)) == pytest.approx(1.1856308407, abs=1e-9)
    assert np.radians(float(field.dip)) == pytest.approx(-1.2584221541, abs=1e-9)


# GeographicLib 2.5 `MagneticField` (C. Karney's independent implementation), as recorded in
# clickr/SwiftGeographicLib Tests/MagneticModelTests: `echo 2025-08-16 -31.93980 115.96650 |
# MagneticField -n NAME` → D, I (deg, 0.01°), H, X, Y, Z, F (nT, 0.1 nT); height 0 above the
# ellipsoid.
GEOGRAPHICLIB_PERTH = {
    "wmm2025": (-1.48, -65.83, 23940.6, 23932.6, -617.1, -53343.1, 58469.1),
    "igrf14": (-1.49, -65.82, 23943.1, 23934.9, -624.6, -53326.7, 58455.2),
}


@pytest.mark.parametrize("model", ["wmm2025", "igrf14"])
def test_geographiclib_values_at_perth(model: str) -> None:
    dec, inc, h, x, y, z, f = GEOGRAPHICLIB_PERTH[model]
    field = reference_field(-31.93980, 115.96650, 0.0, dt.date(2025, 8, 16), model=model)  # type: ignore[arg-type]
    assert float(field.declination) == pytest.approx(dec, abs=DEG_PRINTED)
    assert float(field.dip) == pytest.approx(inc, abs=DEG_PRINTED)
    assert float(field.horizontal) == pytest.approx(h, abs=NT_PRINTED)
    assert float(field.north) == pytest.approx(x, abs=NT_PRINTED)
    assert float(field.east) == pytest.approx(y, abs=NT_PRINTED)
    assert float(field.down) == pytest.approx(z, abs=NT_PRINTED)
    assert float(field.total_field) == pytest.approx(f, abs=NT_PRINTED)


def test_engineering_reference_point() -> None:
    """ENGINEERING.md: 61.25° N 73.4° E on 2026-11-21: F ≈ 59,731 nT, dip ≈ 78.29°, D ≈ 17.0°."""
    field = reference_field(61.25, 73.4, 0.0, dt.date(2026, 11, 21))
    assert float(field.total_field) == pytest.approx(59731.0, abs=0.5)
    assert float(field.dip) == pytest.approx(78.29, abs=0.005)
    assert float(field.declination) == pytest.approx(17.0, abs=0.05)
    igrf = reference_field(61.25, 73.4, 0.0, dt.date(2026, 11, 21), model="igrf14")
    assert float(igrf.total_field) == pytest.approx(59731.0, abs=100.0)
    assert float(igrf.dip) == pytest.approx(78.29, abs=0.5)
    assert float(igrf.declination) == pytest.approx(17.0, abs=0.5)


def test_igrf14_and_wmm2025_agree_within_their_known_difference() -> None:
    """Both models come from the same 2024 data: they differ by tens of nT and hundredths of a
    degree away from the magnetic poles (bounds: 100 nT, 0.5°)."""
    rng = np.random.default_rng(7)
    lat = rng.uniform(-70.0, 75.0, 60)
    lon = rng.uniform(-180.0, 180.0, 60)
    h = rng.uniform(-5000.0, 3000.0, 60)
    dates = [dt.date(2025, 3, 1), dt.date(2027, 6, 30), dt.date(2029, 12, 31)]
    for date in dates:
        wmm = reference_field(lat, lon, h, date)
        igrf = reference_field(lat, lon, h, date, model="igrf14")
        steady = wmm.horizontal > 6000.0  # declination is ill-conditioned near the dip poles
        assert np.abs(igrf.ned() - wmm.ned()).max() < 100.0
        assert np.abs(igrf.total_field - wmm.total_field).max() < 100.0
        assert np.abs(igrf.dip - wmm.dip).max() < 0.5
        assert np.abs(igrf.declination - wmm.declination)[steady].max() < 0.5


@pytest.mark.parametrize("model", ["wmm2025", "igrf14"])
def test_element_identities_are_exact(model: str) -> None:
    rng = np.random.default_rng(3)
    lat = rng.uniform(-90.0, 90.0, 200)
    lon = rng.uniform(-180.0, 540.0, 200)
    h = rng.uniform(-8000.0, 10_000.0, 200)
    f = reference_field(lat, lon, h, dt.date(2026, 5, 17), model=model)  # type: ignore[arg-type]
    dip, dec = np.radians(f.dip), np.radians(f.declination)

    def same(a: np.ndarray, b: np.ndarray) -> None:
        assert np.all(np.abs(a - b) <= 1e-11 * f.total_field)

    same(f.north, f.horizontal * np.cos(dec))
    same(f.east, f.horizontal * np.sin(dec))
    same(f.down, f.total_field * np.sin(dip))
    same(f.horizontal, f.total_field * np.cos(dip))
    np.testing.assert_allclose(f.horizontal, np.hypot(f.north, f.east), rtol=1e-14)
    np.testing.assert_allclose(f.total_field, np.linalg.norm(f.ned(), axis=-1), rtol=1e-14)
    assert np.all((np.abs(f.dip) <= 90.0) & (np.abs(f.declination) <= 180.0))


def test_reference_round_trips_through_the_site_model() -> None:
    field = reference_field(61.25, 73.4, 120.0, dt.date(2026, 11, 21))
    ref = field.reference()
    assert isinstance(ref, MagneticReference)
    assert ref.total_field == float(field.total_field)
    assert ref.dip == float(field.dip)
    assert ref.declination == float(field.declination)
    np.testing.assert_allclose(ref.ned(), field.ned(), rtol=1e-12)
    site = Site(latitude=61.25, longitude=73.4, date=dt.date(2026, 11, 21), magnetic=ref)
    assert site.magnetic == ref
    one_element = reference_field([61.25], [73.4], [120.0], dt.date(2026, 11, 21))
    assert one_element.reference() == ref


def test_reference_needs_a_single_point() -> None:
    field = reference_field([61.0, 62.0], 73.4, 0.0, dt.date(2026, 1, 1))
    with pytest.raises(GeomagneticInputError, match=r"single point.*\(2,\)"):
        field.reference()


@pytest.mark.parametrize("model", ["wmm2025", "igrf14"])
def test_broadcasting_and_per_point_dates_equal_point_calls(model: str) -> None:
    lat = np.array([[61.25], [-33.9], [10.0]])
    lon = np.array([73.4, 18.4, -95.0, 250.0])
    dates = np.array(["2025-02-01", "2026-11-21T06:00", "2028-02-29", "2029-12-31T23:00"])
    if model == "igrf14":
        dates[0] = "2019-06-15"  # spans two IGRF intervals (DGRF2015–DGRF2020, 2025–2030)
    field = reference_field(lat, lon, 250.0, dates.astype("datetime64[us]"), model=model)  # type: ignore[arg-type]
    assert field.north.shape == (3, 4)
    for i in range(3):
        for j in range(4):
            one = reference_field(lat[i, 0], lon[j], 250.0, dates[j], model=model)  # type: ignore[arg-type]
            np.testing.assert_allclose(field.ned()[i, j], one.ned(), rtol=0, atol=1e-7)


def test_igrf14_interpolates_linearly_in_decimal_years_between_knots() -> None:
    """IGRF is linear in time between its 5-yearly knots (and exactly its knot values there)."""
    lat, lon = 51.5, -0.1
    a = reference_field(lat, lon, 0.0, dt.date(2020, 1, 1), model="igrf14").ned()
    b = reference_field(lat, lon, 0.0, dt.date(2025, 1, 1), model="igrf14").ned()
    mid = reference_field(lat, lon, 0.0, at_decimal_year(2022.5), model="igrf14").ned()
    np.testing.assert_allclose(mid, (a + b) / 2.0, rtol=0, atol=1e-8)


def test_longitude_is_periodic_and_height_is_in_metres() -> None:
    date = dt.date(2026, 3, 3)
    east = reference_field(45.0, 240.0, 0.0, date).ned()
    west = reference_field(45.0, -120.0, 0.0, date).ned()
    np.testing.assert_allclose(east, west, rtol=0, atol=1e-8)
    ground = reference_field(45.0, 10.0, 0.0, date)
    high = reference_field(45.0, 10.0, 1000.0, date)
    gradient = float(high.total_field - ground.total_field)  # nT per km
    assert -40.0 < gradient < -10.0  # the main field falls by ~20–30 nT/km near the surface


@pytest.mark.parametrize("model", ["wmm2025", "igrf14"])
def test_poles_are_finite_and_in_their_own_hemisphere(model: str) -> None:
    """Regression: wmm-calculator 1.4.4 puts points within 0.0018° of the south pole at the
    north pole, and ppigrf divides by zero at the poles."""
    lat = np.array([90.0, 89.999, -89.999, -90.0])
    f = reference_field(lat, 30.0, 0.0, dt.date(2026, 6, 1), model=model)  # type: ignore[arg-type]
    assert np.isfinite(f.ned()).all()
    assert (f.down[:2] > 50_000.0).all()  # field points down near the north (magnetic) pole
    assert (f.down[2:] < -45_000.0).all()  # and up near the south one
    np.testing.assert_allclose(f.ned()[0], f.ned()[1], atol=10.0)
    np.testing.assert_allclose(f.ned()[3], f.ned()[2], atol=10.0)


def test_model_and_library_version_are_recorded() -> None:
    wmm = reference_field(0.0, 0.0, 0.0, dt.date(2026, 1, 1))
    igrf = reference_field(0.0, 0.0, 0.0, dt.date(2026, 1, 1), model="igrf14")
    assert wmm.model == "WMM2025"
    assert wmm.model_version == f"wmm-calculator {importlib.metadata.version('wmm-calculator')}"
    assert igrf.model == "IGRF14"
    assert igrf.model_version == f"ppigrf {importlib.metadata.version('ppigrf')}"
    info = field_model("wmm2025")
    assert (info.name, info.valid_from, info.valid_to) == (
        "WMM2025",
        dt.date(2025, 1, 1),
        dt.date(2030, 1, 1),
    )
    assert field_model("igrf14").valid_from == dt.date(1900, 1, 1)


def test_ppigrf_ships_the_igrf14_knots_the_interpolation_assumes() -> None:
    from pathlib import Path

    import ppigrf  # type: ignore[import-untyped]

    g, _ = ppigrf.ppigrf.read_shc(str(Path(ppigrf.__file__).with_name("IGRF14.shc")))
    knots = [t.to_pydatetime() for t in g.index]
    assert knots == [dt.datetime(year, 1, 1) for year in range(1900, 2031, 5)]


@pytest.mark.parametrize(
    ("model", "date"),
    [
        ("wmm2025", dt.date(2024, 12, 31)),
        ("wmm2025", dt.date(2030, 1, 1)),
        ("igrf14", dt.date(1899, 12, 31)),
        ("igrf14", dt.date(2030, 1, 1)),
    ],
)
def test_dates_outside_the_model_raise(model: str, date: dt.date) -> None:
    info = field_model(model)  # type: ignore[arg-type]
    with pytest.raises(ModelValidityError) as caught:
        reference_field(61.0, 73.0, 0.0, date, model=model)  # type: ignore[arg-type]
    text = str(caught.value)
    assert info.name in text
    assert str(info.valid_from) in text and str(info.valid_to) in text
    assert str(date) in text
    assert isinstance(caught.value, GyropipeError)


def test_validity_edges_and_arrays() -> None:
    reference_field(61.0, 73.0, 0.0, dt.datetime(2029, 12, 31, 23, 59))
    reference_field(61.0, 73.0, 0.0, dt.date(2025, 1, 1))
    reference_field(61.0, 73.0, 0.0, dt.date(1900, 1, 1), model="igrf14")
    dates = ["2026-01-01", "2031-05-05", "2032-01-01"]
    with pytest.raises(ModelValidityError, match=r"2031-05-05 \(and 1 more\)"):
        reference_field(61.0, 73.0, 0.0, dates)


def test_timezone_aware_datetimes_are_taken_in_utc() -> None:
    aware = dt.datetime(2026, 1, 1, 3, tzinfo=dt.timezone(dt.timedelta(hours=5)))
    naive = dt.datetime(2025, 12, 31, 22)
    a = reference_field(61.0, 73.0, 0.0, aware).ned()
    b = reference_field(61.0, 73.0, 0.0, naive).ned()
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("lat", "lon", "h", "date", "message"),
    [
        (90.5, 0.0, 0.0, "2026-01-01", "latitude must be within"),
        (-91.0, 0.0, 0.0, "2026-01-01", "latitude must be within"),
        (np.nan, 0.0, 0.0, "2026-01-01", "latitude must be finite"),
        (0.0, np.inf, 0.0, "2026-01-01", "longitude must be finite"),
        (0.0, 0.0, np.nan, "2026-01-01", "height must be finite"),
        ("north", 0.0, 0.0, "2026-01-01", "latitude must be numeric"),
        (0.0, 0.0, 0.0, "yesterday", "not a date"),
        (0.0, 0.0, 0.0, ["2026-01-01", "NaT"], "missing date"),
        ([0.0, 1.0], [0.0, 1.0, 2.0], 0.0, "2026-01-01", "do not broadcast"),
    ],
)
def test_invalid_inputs_raise(
    lat: object, lon: object, h: object, date: object, message: str
) -> None:
    with pytest.raises(GeomagneticInputError, match=message):
        reference_field(lat, lon, h, date)  # type: ignore[arg-type]


def test_unknown_model_raises() -> None:
    with pytest.raises(GeomagneticInputError, match="unknown geomagnetic model 'emm2017'"):
        reference_field(0.0, 0.0, 0.0, "2026-01-01", model="emm2017")  # type: ignore[arg-type]


def test_empty_input_gives_empty_field() -> None:
    f = reference_field(np.zeros(0), np.zeros(0), 0.0, "2026-01-01")
    assert f.north.shape == (0,) and f.declination.shape == (0,)


def test_decimal_year() -> None:
    assert decimal_year(dt.datetime(2027, 7, 2, 12)) == 2027.5
    assert decimal_year(dt.date(2028, 1, 1)) == 2028.0
    assert decimal_year("2028-12-31T12:00") == pytest.approx(2028.0 + 365.5 / 366.0, abs=1e-12)
    np.testing.assert_allclose(
        decimal_year(["2025-01-01", "2025-07-02T12:00"]), [2025.0, 2025.5], atol=1e-12
    )


def test_wmm_uncertainty_declination_is_computed_not_taken_from_the_library() -> None:
    field = reference_field([61.25, 0.0], [73.4, 0.0], 0.0, dt.date(2026, 11, 21))
    u = field.uncertainty()
    expected = np.hypot(0.26, 5417.0 / field.horizontal)
    np.testing.assert_allclose(u.declination, expected, rtol=1e-14)
    assert u.declination[0] == pytest.approx(np.hypot(0.26, 5417.0 / 12119.9), abs=1e-3)
    np.testing.assert_array_equal(u.total_field, [138.0, 138.0])
    np.testing.assert_array_equal(u.dip, [0.20, 0.20])
    igrf = reference_field(61.25, 73.4, 0.0, dt.date(2026, 11, 21), model="igrf14")
    with pytest.raises(GeomagneticInputError, match="IGRF14 publishes no uncertainty"):
        igrf.uncertainty()


def test_blackout_zone_is_visible_through_the_horizontal_field() -> None:
    """The library's blackout-zone warning is silenced; H tells the caller instead."""
    near_dip_pole = reference_field(85.0, 136.0, 0.0, dt.date(2026, 1, 1))
    assert float(near_dip_pole.horizontal) < BLACKOUT_ZONE_NT


@pytest.mark.process("what a fresh interpreter imports")
def test_importing_the_module_does_not_import_the_libraries() -> None:
    code = (
        "import sys, pipeline.earth.geomagnetic, pipeline.earth.grid; "
        "print(sorted({'wmm', 'ppigrf', 'pyproj'} & set(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
