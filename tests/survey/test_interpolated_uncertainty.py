"""Interpolating a trajectory that carries position uncertainty neither drops nor invents σ:
a point at a survey station keeps the station's covariance and ellipse columns exactly (the
error model run directly on the stations), a point between stations gets NaN in every one of
them, flagged ``interpolated`` and warned of by stage and columns (its covariance is not an
interpolation of its neighbours'); the error model and tie-on statements go with them.
Driven through the CLI (interpolate_md after position_uncertainty) and ``gp.interpolate``."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import SurveyCheckWarning
from tests_support import ROOT, gyropipe_cli, stage, write_pipeline

STATIONS = ROOT / "examples" / "stations-j-well.csv"
SIGMA = (
    "cov_nn",
    "cov_ne",
    "cov_nv",
    "cov_ee",
    "cov_ev",
    "cov_vv",
    "ellipse_major",
    "ellipse_minor",
    "ellipse_azimuth",
    "sigma_v",
    "ellipse_major_conf",
    "ellipse_minor_conf",
    "vertical_conf",
)
TIE_KEY = b"gyropipe.uncertainty_tie_on"
MODEL_KEY = b"gyropipe.error_model"


def _with_sigma(stations: pd.DataFrame, **params: object) -> pd.DataFrame:
    """The error model run directly on the stations (no interpolation)."""
    out: pd.DataFrame = gp.position_uncertainty(
        gp.minimum_curvature(stations), latitude=61.25, **params
    )
    return out


def test_points_at_stations_keep_their_sigma_and_points_between_have_none(tmp_path: Path):
    spec = write_pipeline(
        tmp_path,
        [
            stage("read", "read_stations"),
            stage("trajectory", "minimum_curvature", {"stations": "read.stations"}),
            stage(
                "sigma",
                "position_uncertainty",
                {"trajectory": "trajectory.trajectory"},
                ["trajectory"],
                latitude=61.25,
            ),
            stage(
                "every25",
                "interpolate_md",
                {"trajectory": "sigma.trajectory"},
                ["points"],
                spacing=25.0,
                include_stations=True,
            ),
        ],
    )
    done = gyropipe_cli("run", spec, "--input", STATIONS, "--out", tmp_path / "out", check=True)
    points = pq.read_table(tmp_path / "out" / "every25.points.parquet")
    direct = _with_sigma(gp.read(STATIONS))
    md = points.column("md").to_numpy()
    at_station = np.isin(md, direct["md"].to_numpy())
    assert at_station.sum() == len(direct) and (~at_station).sum() > 10
    np.testing.assert_array_equal(points.column("interpolated").to_numpy(), ~at_station)
    rows = np.searchsorted(direct["md"].to_numpy(), md[at_station])
    for name in SIGMA:
        got = points.column(name).to_numpy()
        np.testing.assert_allclose(got[at_station], direct[name].to_numpy()[rows], rtol=1e-12)
        assert np.isnan(got[~at_station]).all(), name
    # what the columns state goes with them
    sigma = pq.read_table(tmp_path / "out" / "sigma.trajectory.parquet")
    assert (
        points.schema.field("cov_nn").metadata[MODEL_KEY]
        == (sigma.schema.field("cov_nn").metadata[MODEL_KEY])
    )
    assert json.loads(points.schema.metadata[TIE_KEY]) == json.loads(sigma.schema.metadata[TIE_KEY])
    said = re.search(
        r"stage 'every25': (\d+) of (\d+) points lie between survey stations", done.stderr
    )
    assert said and (int(said[1]), int(said[2])) == ((~at_station).sum(), md.size), done.stderr
    assert ", ".join(SIGMA) + " are NaN" in done.stderr


def test_tvd_crossings_at_a_station_keep_its_sigma():
    direct = _with_sigma(gp.read(STATIONS))
    station_tvd = float(direct["tvd"].iloc[20])
    between = 0.5 * (station_tvd + float(direct["tvd"].iloc[21]))
    with pytest.warns(SurveyCheckWarning, match=r"stage 'interpolate_tvd': 1 of 2 points"):
        got = gp.interpolate(direct, tvd=[station_tvd, between])
    assert got["md"].iloc[0] == direct["md"].iloc[20]
    assert got["interpolated"].tolist() == [False, True]
    for name in SIGMA:
        assert got[name].iloc[0] == direct[name].iloc[20], name
        assert np.isnan(got[name].iloc[1]), name
    assert got.attrs["uncertainty"]["error_model"] == direct.attrs["uncertainty"]["error_model"]


def test_a_point_below_a_station_outside_the_model_is_flagged_outside_too():
    stations = pd.DataFrame(
        {"md": [0.0, 100.0, 200.0, 300.0], "inc": [0.0, 45.0, 90.0, 90.0], "azi": [0.0] * 4}
    )
    stations.attrs["north_reference"] = "true"
    direct = _with_sigma(stations, outside_validity="flag")  # GYRO-NS holds to 89°
    assert direct["outside_validity"].tolist() == [False, False, True, True]
    with pytest.warns(SurveyCheckWarning, match="2 of 3 points lie between survey stations"):
        got = gp.interpolate(direct, md=[150.0, 200.0, 250.0])
    assert got["outside_validity"].tolist() == [False, True, True]
    assert got["interpolated"].tolist() == [True, False, True]
    assert got["cov_nn"].isna().all()  # at 200 m the station's own: outside, no σ


def test_a_trajectory_without_sigma_interpolates_as_before():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = gp.interpolate(gp.minimum_curvature(gp.read(STATIONS)), spacing=50.0)
    assert list(got.columns) == ["md", "inc", "azi", "tvd", "north", "east"]


def test_a_summary_of_a_trajectory_of_interpolated_points_counts_its_stations(tmp_path: Path):
    """The points integrated again (minimum_curvature of interpolate_md's points) keep their
    ``interpolated`` flag with the σ they carry; summary.json counts and measures the survey
    stations, the points apart — as the stations' own survey says."""
    spec = write_pipeline(
        tmp_path,
        [
            stage("read", "read_stations"),
            stage("trajectory", "minimum_curvature", {"stations": "read.stations"}),
            stage(
                "sigma",
                "position_uncertainty",
                {"trajectory": "trajectory.trajectory"},
                latitude=61.25,
            ),
            stage(
                "every25",
                "interpolate_md",
                {"trajectory": "sigma.trajectory"},
                spacing=25.0,
                include_stations=True,
            ),
            stage("again", "minimum_curvature", {"stations": "every25.points"}, ["trajectory"]),
            stage(
                "summary",
                "export",
                {"trajectory": "again.trajectory"},
                writer="json_summary",
                filename="summary.json",
            ),
            stage("report", "report", {"trajectory": "again.trajectory"}, formats=["html"]),
        ],
    )
    gyropipe_cli("run", spec, "--input", STATIONS, "--out", tmp_path / "out", check=True)
    again = pq.read_table(tmp_path / "out" / "again.trajectory.parquet")
    doc = json.loads((tmp_path / "out" / "summary.json").read_text())
    direct = _with_sigma(gp.read(STATIONS))
    between = again.num_rows - len(direct)
    assert between > 10 and int(np.sum(again.column("interpolated").to_numpy())) == between
    assert (doc["station_count"], doc["interpolated_points"]) == (len(direct), between)
    (survey,) = doc["surveys"]
    assert survey["station_count"] == len(direct)
    assert survey["final"]["md"] == direct["md"].iloc[-1]
    # the largest DLS over the stations' courses of at least 10 m, from the stations alone
    md, dls = direct["md"].to_numpy(), direct["dls"].to_numpy()
    counted = np.r_[False, np.diff(md) >= 10.0]
    worst = int(np.argmax(np.where(counted, dls, -np.inf)))
    assert survey["max_dls"]["dls"] == pytest.approx(dls[worst], rel=1e-9)
    assert survey["max_dls"]["md"] == md[worst]
    assert survey["max_dls"]["courses_not_counted"] == int((~counted[1:]).sum())
    stated = doc["uncertainty"]
    assert stated["stations_without_sigma"] == int(direct["ellipse_major"].isna().sum())
    assert stated["interpolated_points"] == between
    assert stated["at_td"]["semi_major"] == pytest.approx(direct["ellipse_major"].iloc[-1], 1e-4)
    html = (tmp_path / "out" / "report.html").read_text()
    assert f"{between} row(s) are points interpolated between survey stations" in html
