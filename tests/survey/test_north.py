"""North-reference conversions: signs, round trips, table relabelling, the stage."""

from __future__ import annotations

import datetime as dt
from typing import Any

import numpy as np
import pytest

from pipeline.stages.stations import NorthReferenceParams, north_reference_stage
from pipeline.survey.north import convert_azimuth, convert_table
from pipeline.tables import Stations
from pipeline.well import WellMetadata
from tests_support import stage_context


def test_declination_sign() -> None:
    # declination 17° E: magnetic 10° is true 27°
    azi, label = convert_azimuth(10.0, "magnetic", "true", declination_deg=17.0)
    assert label == "true"
    assert azi == pytest.approx(27.0)
    assert convert_azimuth(27.0, "true", "magnetic", declination_deg=17.0)[0] == pytest.approx(10.0)


def test_convergence_sign() -> None:
    # γ = +2° (grid north east of true north): true 27° is grid 25°
    assert convert_azimuth(27.0, "true", "grid", convergence_deg=2.0)[0] == pytest.approx(25.0)
    assert convert_azimuth(25.0, "grid", "true", convergence_deg=2.0)[0] == pytest.approx(27.0)
    # magnetic → grid: A_mag + D − γ, wrapped
    got, label = convert_azimuth(
        355.0, "magnetic", "grid", convergence_deg=-3.0, declination_deg=4.0
    )
    assert label == "grid"
    assert got == pytest.approx(2.0)


def test_round_trips() -> None:
    rng = np.random.default_rng(0)
    azi = rng.uniform(0.0, 360.0, 100)
    kw = {"convergence_deg": 1.7, "declination_deg": -12.3}
    for a in ("true", "grid", "magnetic"):
        for b in ("true", "grid", "magnetic"):
            there, _ = convert_azimuth(azi, a, b, **kw)  # type: ignore[arg-type]
            back, _ = convert_azimuth(there, b, a, **kw)  # type: ignore[arg-type]
            assert np.all((there >= 0.0) & (there < 360.0))
            diff = np.mod(back - azi + 180.0, 360.0) - 180.0
            np.testing.assert_allclose(diff, 0.0, atol=1e-12)


def test_missing_correction_and_unknown_reference() -> None:
    with pytest.raises(ValueError, match="declination"):
        convert_azimuth(1.0, "magnetic", "true")
    with pytest.raises(ValueError, match="convergence"):
        convert_azimuth(1.0, "true", "grid")
    with pytest.raises(ValueError, match="unknown north reference"):
        convert_azimuth(1.0, "sideways", "true")


def stations(reference: str) -> Any:
    return Stations.compiled().make_table(
        {"md": [0.0, 30.0], "inc": [0.0, 5.0], "azi": [10.0, 350.0]}, north_reference=reference
    )


def test_convert_table_relabels() -> None:
    out = convert_table(stations("magnetic"), "true", declination_deg=17.0)
    Stations.compiled().validate(out)
    assert out.schema.field("azi").metadata[b"north_reference"] == b"true"
    np.testing.assert_allclose(out.column("azi").to_numpy(), [27.0, 7.0])
    np.testing.assert_array_equal(out.column("inc").to_numpy(), [0.0, 5.0])


def test_convert_table_turns_the_files_own_positions() -> None:
    """A listing's north/east are in its azimuths' reference: converted with them (a
    point 100 m along true azimuth 10° is 100 m along magnetic azimuth 10° − 17°)."""
    table = stations("true").append_column("north", [[0.0, 100 * np.cos(np.radians(10.0))]])
    table = table.append_column("east", [[0.0, 100 * np.sin(np.radians(10.0))]])
    out = convert_table(table, "magnetic", declination_deg=17.0)
    np.testing.assert_allclose(out.column("azi").to_numpy(), [353.0, 333.0])
    turned = np.radians(-7.0)
    np.testing.assert_allclose(out.column("north").to_numpy(), [0.0, 100 * np.cos(turned)])
    np.testing.assert_allclose(out.column("east").to_numpy(), [0.0, 100 * np.sin(turned)])


def test_stage_given_declination() -> None:
    reported: list[WellMetadata] = []
    ctx: Any = stage_context(WellMetadata(), update_well=reported.append)
    params = NorthReferenceParams(target="true", declination=17.0)
    out = north_reference_stage({"stations": stations("magnetic")}, params, ctx)["stations"]
    np.testing.assert_allclose(out.column("azi").to_numpy(), [27.0, 7.0])
    # the run's well learns the north reference, the declination used and that the azimuths
    # now have it applied (true north: magnetic + 17°), nothing else
    assert [w.model_dump(exclude_unset=True) for w in reported] == [
        {"north_reference": "true", "declination": 17.0, "declination_applied": 17.0}
    ]


def test_stage_from_well_header() -> None:
    from pipeline.earth.geomagnetic import reference_field
    from pipeline.earth.grid import grid_convergence

    well = WellMetadata(latitude=55.0, longitude=75.0, survey_date=dt.date(2026, 3, 1))
    ctx: Any = stage_context(well, update_well=lambda found: None)
    params = NorthReferenceParams(target="grid", crs="EPSG:32643")
    out = north_reference_stage({"stations": stations("magnetic")}, params, ctx)["stations"]
    d = float(reference_field(55.0, 75.0, 0.0, dt.date(2026, 3, 1)).declination)
    g = float(grid_convergence(55.0, 75.0, "EPSG:32643"))
    np.testing.assert_allclose(
        out.column("azi").to_numpy(), np.mod([10.0 + d - g, 350.0 + d - g], 360.0)
    )
    assert out.schema.field("azi").metadata[b"north_reference"] == b"grid"


def test_stage_needs_a_source_for_corrections() -> None:
    ctx: Any = stage_context(WellMetadata(), update_well=lambda found: None)
    with pytest.raises(ValueError, match="declination"):
        north_reference_stage(
            {"stations": stations("magnetic")}, NorthReferenceParams(target="true"), ctx
        )
    # nothing to convert: no correction needed
    out = north_reference_stage(
        {"stations": stations("true")}, NorthReferenceParams(target="true"), ctx
    )
    np.testing.assert_allclose(out["stations"].column("azi").to_numpy(), [10.0, 350.0])
