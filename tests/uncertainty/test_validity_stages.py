"""Validity ranges in clearance and the definitive survey (issue 29): a reference or offset
station outside its tool model's range, or a run's station outside its model's, is refused
(naming the well or run) or flagged (NaN σ and SF, and an ``outside_validity`` column)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import pipeline as gp
from pipeline.errors import StageError

DATA = Path(__file__).parent / "data"


def _stations(md_from: float = 0.0, md_to: float = np.inf, east: float = 0.0) -> pd.DataFrame:
    """ISCWSA test well #1 (90° from MD 5400 m) between two MDs, true azimuths."""
    data = json.loads((DATA / "iscwsa-well-1-mwdrev5.json").read_text())
    frame = pd.DataFrame({k: data["survey"][k] for k in ("md", "inc", "azi")})
    frame = frame[(frame.md >= md_from) & (frame.md <= md_to)].reset_index(drop=True)
    frame.attrs["north_reference"] = "true"
    return frame


def _clearance(reference_model: str, offset_model: str, **params: object) -> pd.DataFrame:
    """Well #1 against itself 30 m east."""
    out: pd.DataFrame = gp.clearance(
        _stations(),
        {"twin": _stations()},
        offset_model=offset_model,
        offset_hole_diameter=0.3,
        offset_position={"twin": (0.0, 30.0)},
        reference_model=reference_model,
        reference_hole_diameter=0.3,
        latitude=60.0,
        **params,
    )
    return out


@pytest.mark.parametrize(
    ("reference", "offset", "words"),
    [("GYRO-NS", "GYRO-NS-CT", "the reference"), ("GYRO-NS-CT", "GYRO-NS", "offset well 'twin'")],
)
def test_clearance_refuses_a_well_outside_its_model(reference: str, offset: str, words: str):
    with pytest.raises(StageError) as info:
        _clearance(reference, offset)
    message = str(info.value)
    assert f"{words}: tool model GYRO-NS holds for inclinations 0–89°" in message, message
    assert "MD 5400 m" in message


def test_clearance_flags_the_reference_outside_its_model():
    frame = _clearance("GYRO-NS", "GYRO-NS-CT", outside_validity="flag")
    flagged = frame.outside_validity.to_numpy()
    np.testing.assert_array_equal(flagged, frame.md.to_numpy() >= 5400.0)
    assert frame.sf[flagged].isna().all() and (frame.level[flagged] == "fail").all()
    assert frame.sf[~flagged].notna().all() and frame.sigma_s[~flagged].max() < 1000.0


def test_clearance_flags_an_offset_beyond_its_model():
    frame = _clearance("GYRO-NS-CT", "GYRO-NS", outside_validity="flag")
    flagged = frame.outside_validity.to_numpy()
    # the closest point lies on the offset's course into, or beyond, its station at 5400 m
    np.testing.assert_array_equal(flagged, frame.offset_md.to_numpy() > 5370.0)
    assert frame.sf[flagged].isna().all() and frame.sf[~flagged].notna().all()


RUNS = {"upper": _stations(md_to=3000.0), "lower": _stations(md_from=3000.0)}


def test_definitive_survey_refuses_a_run_outside_its_model():
    with pytest.raises(StageError, match="run 'lower': tool model GYRO-NS holds for incl"):
        gp.definitive_survey(RUNS, latitude=60.0)


def test_definitive_survey_flags_from_the_first_station_outside():
    survey = gp.definitive_survey(RUNS, latitude=60.0, outside_validity="flag").survey
    frame = survey.to_pandas() if hasattr(survey, "to_pandas") else survey
    flagged = frame.outside_validity.to_numpy()
    np.testing.assert_array_equal(flagged, frame.md.to_numpy() >= 5400.0)
    assert frame.cov_nn[flagged].isna().all() and frame.ellipse_major[~flagged].notna().all()
    assert frame.ellipse_major[~flagged].max() < 1000.0
    assert set(frame.run[flagged]) == {"lower"} and frame.north.notna().all()
