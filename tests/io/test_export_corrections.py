"""The corrections exports state: the north_reference stage uses the well's declination and
grid convergence, records what it applied (and the new north reference) in the run's well
metadata, and refuses a correction contradicting the well's."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pytest
from export_support import run_yaml

from pipeline.errors import StageError
from pipeline.survey.north import declination_at
from pipeline.well import WellMetadata

STATIONS = "MD (m),Inc (deg),Azimuth Magnetic (deg)\n0,0,355\n100,5,355\n200,10,10\n"
PIPELINE = """
name: corrections
version: "1.0"
inputs:
  stations: {{description: magnetic stations}}
stages:
  - id: read
    uses: read_stations
  - id: true_north
    uses: north_reference
    inputs: {{stations: read.stations}}
    with: {with_}
  - id: trajectory
    uses: minimum_curvature
    inputs: {{stations: true_north.stations}}
  - id: witsml
    uses: write
    inputs: {{table: trajectory.trajectory}}
    with: {{writer: witsml}}
"""


def run(tmp_path: Path, with_: str, well: WellMetadata) -> tuple[np.ndarray, WellMetadata, str]:
    src = tmp_path / "mag.csv"
    src.write_text(STATIONS)
    result = run_yaml(PIPELINE.format(with_=with_), {"stations": src}, tmp_path / "out", well)
    azi = result.tables[("trajectory", "trajectory")].column("azi").to_numpy()
    return azi, result.well, (result.out_dir / "witsml.xml").read_text()


def test_the_wells_declination_is_applied_and_stated(tmp_path: Path):
    azi, well, xml = run(tmp_path, "{target: true}", WellMetadata(well="M", declination=10.0))
    np.testing.assert_allclose(azi, [5.0, 5.0, 20.0], atol=1e-12)  # A_true = A_mag + D
    assert (well.declination, well.north_reference) == (10.0, "true")
    assert '<magDeclUsed uom="dega">10.0</magDeclUsed>' in xml
    assert "<aziRef>true north</aziRef>" in xml


def test_a_modelled_declination_is_recorded(tmp_path: Path):
    site = WellMetadata(well="M", latitude=61.25, longitude=73.4, survey_date=dt.date(2026, 11, 21))
    azi, well, xml = run(tmp_path, "{target: true, model: wmm2025}", site)
    expected = declination_at(61.25, 73.4, dt.date(2026, 11, 21))
    assert 16.0 < expected < 18.0  # ≈ 17.0° at this site (ENGINEERING.md)
    assert well.declination == expected
    np.testing.assert_allclose(azi[-1], 10.0 + expected, atol=1e-12)
    assert f'<magDeclUsed uom="dega">{expected!r}</magDeclUsed>' in xml


def test_a_contradicting_correction_is_refused(tmp_path: Path):
    with pytest.raises(StageError, match=r"declination 9\.0 contradicts the well's declination"):
        run(tmp_path, "{target: true, declination: 9.0}", WellMetadata(declination=10.0))
