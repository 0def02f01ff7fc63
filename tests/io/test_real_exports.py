"""Real exports read for what they mean (issue 28, items 1–4), driven end to end through the
command line (``pipelines/survey.yaml``) and the Python API on files built as vendors write
them (:mod:`vendor_exports`):

* WITSML ``gridCorUsed``/``magDeclUsed`` (and the per-station ``stnGridCorUsed``…) are the
  corrections applied to the azimuths, never the site's convergence or declination: a
  conversion to grid north takes γ from the CRS at the wellhead (expected values from
  pyproj directly), a user's γ is not "contradicted" by an applied 0, exports state what
  was applied; a LAS ``GRIDCORR`` (a vendor's correction, of no agreed sign) is neither γ;
* several WITSML trajectories are dated by the earliest ``dTimTrajStart``; magnetic ones
  of different days with no declination stated are refused (each needs its own day's), and
  of other ones a declination or field at one date (a conversion to magnetic north, an MWD
  model) is refused; reports and exports state the range;
* ``-999.25``-family null markers are nulls in every reader; a station without an azimuth
  is a located error, or left out when the user asks;
* implausible angles and radians declared degrees (or the reverse) are located errors;
* the survey tool of the stations reaches the exports and the report;
* a header length without a unit (a CSV title's, a LAS elevation) is in the file's one
  length unit, else refused; a header null is no value;
* a LAS azimuth description's words about corrections (``mag dec applied``, ``not grid
  corrected``) name no north reference.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import lasio
import numpy as np
import pyarrow.parquet as pq
import pyproj
import pytest
import yaml
from vendor_exports import CRS, SITE, Survey, survey_pipeline, witsml

import pipeline as gp
import pipeline.cli
from pipeline.errors import InputFileError, InputFileWarning, SurveyCheckWarning
from pipeline.spec import load_spec
from pipeline.survey.north import declination_at
from tests_support import CliResult, gyropipe_cli

NS = {"w": "http://www.witsml.org/schemas/1series"}
GRID = {"id": "grid", "uses": "north_reference", "with": {"target": "grid", "crs": CRS}}
GRID_APPLIED = '<gridCorUsed uom="dega">{}</gridCorUsed>'
WELL_ARGS = ["--well", f"latitude={SITE['latitude']}", "--well", f"longitude={SITE['longitude']}"]


def gamma() -> float:
    """Meridian convergence of EPSG:23031 at the site, deg, straight from pyproj (PROJ)."""
    factors = pyproj.Proj(CRS).get_factors(SITE["longitude"], SITE["latitude"])
    return float(factors.meridian_convergence)


def run(pipeline_yaml: Path, source: Path, out: Path, *extra: str) -> CliResult:
    return gyropipe_cli(
        "run", str(pipeline_yaml), "--input", f"stations={source}", "--out", str(out), *extra
    )


def trajectory_xml(out: Path) -> ET.Element:
    (traj,) = ET.parse(out / "trajectory.xml").getroot().findall("w:trajectory", NS)
    return traj


def measure(traj: ET.Element, name: str) -> tuple[float, str]:
    node = traj.find(f"w:{name}", NS)
    assert node is not None, name
    return float(node.text or ""), node.attrib["uom"]


def las_params(out: Path) -> dict[str, object]:
    return {p.mnemonic: p.value for p in lasio.read(str(out / "trajectory.las")).params}


# ------------------------------------------------------------------- 1. applied corrections


def test_grid_north_takes_the_crs_convergence_not_the_applied_0(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml")  # aziRef true north, gridCorUsed 0 (rad)
    result = run(survey_pipeline(tmp_path, GRID), source, tmp_path / "out", *WELL_ARGS)
    assert result.returncode == 0, result.output
    g = gamma()
    assert -0.96 < g < -0.94  # west of the zone's central meridian (3° E)
    survey = Survey()
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    inclined = survey.inc > 0
    np.testing.assert_allclose(
        trajectory.column("azi").to_numpy()[inclined], (45.0 - g) % 360.0, atol=1e-9
    )
    _, north, east, _ = survey.positions()  # true-north positions; grid ones are turned by -γ
    rad = math.radians(g)
    grid_north = north[-1] * math.cos(rad) + east[-1] * math.sin(rad)
    grid_east = east[-1] * math.cos(rad) - north[-1] * math.sin(rad)
    td = (trajectory.column("north")[-1].as_py(), trajectory.column("east")[-1].as_py())
    np.testing.assert_allclose(td, (grid_north, grid_east), atol=1e-6)
    assert math.hypot(grid_north - north[-1], grid_east - east[-1]) > 17.0  # what was lost
    traj = trajectory_xml(tmp_path / "out")
    assert traj.findtext("w:aziRef", namespaces=NS) == "grid north"
    value, uom = measure(traj, "gridCorUsed")
    assert uom == "dega" and value == pytest.approx(g, abs=1e-12)
    assert measure(traj, "magDeclUsed") == (0.0, "dega")  # the file's: none applied
    params = las_params(tmp_path / "out")
    assert params["GRIDCONV"] == pytest.approx(g, abs=1e-12)
    assert params["GRIDUSED"] == pytest.approx(g, abs=1e-12)
    assert params["NREF"] == "grid"


def test_a_given_convergence_is_not_contradicted_by_an_applied_0(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml")
    given = ["--set", "grid.convergence=-0.9484"]
    result = run(survey_pipeline(tmp_path, GRID), source, tmp_path / "out", *given, *WELL_ARGS)
    assert result.returncode == 0, result.output
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.column("azi").to_numpy()[-1] == pytest.approx(45.9484, abs=1e-9)
    assert measure(trajectory_xml(tmp_path / "out"), "gridCorUsed") == (-0.9484, "dega")


def test_magdeclused_0_is_not_the_sites_declination(tmp_path: Path):
    import ppigrf

    source = witsml(tmp_path / "vendor.xml")  # magDeclUsed 0: gyro azimuths, none applied
    mag = {
        "id": "mag",
        "uses": "north_reference",
        "with": {"target": "magnetic", "model": "igrf14"},
    }
    result = gp.run(
        survey_pipeline(tmp_path, mag), {"stations": source}, well=SITE, out=tmp_path / "out"
    )
    b_east, b_north, _ = ppigrf.igrf(
        SITE["longitude"], SITE["latitude"], 0.0, dt.datetime(2026, 3, 2)
    )
    declination = math.degrees(math.atan2(float(np.ravel(b_east)[0]), float(np.ravel(b_north)[0])))
    assert abs(declination) > 0.3  # a real correction at this site
    azi = result.tables["trajectory.trajectory"].column("azi").to_numpy()
    assert azi[-1] == pytest.approx(45.0 - declination, abs=1e-3)
    assert result.well.declination == pytest.approx(declination, abs=1e-3)
    traj = trajectory_xml(tmp_path / "out")
    assert measure(traj, "magDeclUsed") == (0.0, "dega")  # magnetic azimuths: none applied
    assert traj.findtext("w:aziRef", namespaces=NS) == "magnetic north"


def test_corrections_stated_per_station_are_what_was_applied(tmp_path: Path):
    g = gamma()
    survey = Survey()
    grid_azi = {k: repr(math.radians((45.0 - g) % 360.0)) for k in range(1, survey.md.size)}
    per_station = f'<stnGridCorUsed uom="rad">{math.radians(g)!r}</stnGridCorUsed>'
    source = witsml(
        tmp_path / "grid.xml",
        azi_ref="grid north",
        head="",
        corrections='<stnMagDeclUsed uom="rad">-999.25</stnMagDeclUsed>' + per_station,
        azi_rad={k: v for k, v in grid_azi.items() if survey.inc[k] > 0},
    )
    to_true = {"id": "true", "uses": "north_reference", "with": {"target": "true"}}
    result = run(survey_pipeline(tmp_path, to_true), source, tmp_path / "out")
    assert result.returncode == 0, result.output
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.column("azi").to_numpy()[-1] == pytest.approx(45.0, abs=1e-9)
    assert measure(trajectory_xml(tmp_path / "out"), "gridCorUsed") == (0.0, "dega")
    varying = source.read_text().replace(
        per_station, '<stnGridCorUsed uom="dega">-0.5</stnGridCorUsed>', 1
    )
    source.write_text(varying)
    with pytest.raises(InputFileError, match=r"grid\.xml:\d+ \(column 'stnGridCorUsed'\).*differs"):
        gp.read(source, kind="stations")


def test_a_correction_the_reference_cannot_carry_is_refused(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml", head='<gridCorUsed uom="rad">-0.0165</gridCorUsed>')
    line = next(i for i, t in enumerate(source.read_text().splitlines(), 1) if "gridCorUsed" in t)
    with pytest.raises(InputFileError, match="contradicts aziRef 'true north'") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == line


@pytest.mark.parametrize(
    ("nref", "item", "words"),
    [
        ("TRUE", "GRIDUSED.DEG  -0.95", "GRIDUSED -0.95°: a grid convergence applied contradicts"),
        ("MAGNETIC", "DECLUSED.DEG  2.5", "DECLUSED 2.5°: a declination applied contradicts"),
    ],
)
def test_a_las_correction_the_reference_cannot_carry_is_refused(
    tmp_path: Path, nref: str, item: str, words: str
):
    source = tmp_path / "vendor.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        f"~Well\n STRT.M 0 :\n STOP.M 200 :\n STEP.M 100 :\n NULL. -999.25 :\n NREF. {nref} :\n"
        f" {item} : correction applied to the azimuths\n"
        "~Curve\n DEPT.M : measured depth\n INC.DEG : inclination\n AZI.DEG : azimuth\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    with pytest.raises(InputFileError, match=re.escape(words)) as caught:
        gp.read(source, kind="stations")  # once read, and exported as applied to them
    assert caught.value.line == 10
    source.write_text(source.read_text().replace(item, item.split()[0] + "  0"))
    assert gp.read(source, kind="stations")["azi"].tolist() == [0.0, 45.0, 45.0]  # 0: none


def test_a_las_grid_correction_is_not_taken_for_the_convergence(tmp_path: Path):
    """A vendor's LAS of grid azimuths states the correction it added to the true ones
    (GRIDCORR +0.95° = −γ at this site): read as γ, it turned them 1.9° the wrong way."""
    source = tmp_path / "grid.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.M 0 :\n STOP.M 200 :\n STEP.M 100 :\n NULL. -999.25 :\n NREF. GRID :\n"
        "~Parameter\n GRIDCORR.DEG  0.95 : grid correction\n"
        "~Curve\n DEPT.M : measured depth\n INC.DEG : inclination\n AZI.DEG : azimuth\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    with pytest.warns(InputFileWarning, match=r"grid\.las:11: GRIDCORR '0\.95' left out"):
        stations = gp.read(source, kind="stations")
    assert "grid_convergence" not in stations.attrs["well"]
    to_true = {"id": "true", "uses": "north_reference", "with": {"target": "true", "crs": CRS}}
    result = run(survey_pipeline(tmp_path, to_true), source, tmp_path / "out", *WELL_ARGS)
    assert result.returncode == 0, result.output
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.column("azi").to_numpy()[-1] == pytest.approx(45.0 + gamma(), abs=1e-9)


def test_grid_azimuths_go_back_to_true_only_by_the_convergence_applied(tmp_path: Path):
    head = '<gridCorUsed uom="dega">-0.9</gridCorUsed>'
    source = witsml(tmp_path / "grid.xml", azi_ref="grid north", head=head)
    to_true = {"id": "true", "uses": "north_reference", "with": {"target": "true"}}
    pipe = survey_pipeline(tmp_path, to_true)
    refused = run(pipe, source, tmp_path / "refused", "--set", "true.convergence=-0.95")
    assert refused.returncode != 0
    assert "contradicts the grid convergence applied" in refused.output
    result = run(pipe, source, tmp_path / "out")
    assert result.returncode == 0, result.output
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.column("azi").to_numpy()[-1] == pytest.approx(44.1, abs=1e-9)


def second_trajectory(source: Path, old: str = "", new: str = "") -> int:
    """Append to the vendor's file a copy of its trajectory (another uid and name) with
    ``old`` replaced by ``new``; the line of the copy's opening tag."""
    text = source.read_text()
    block = text[text.index("  <trajectory ") : text.index("</trajectorys>")]
    second = block.replace('uid="DEF-GYRO"', 'uid="DEF-GYRO-2"').replace("survey<", "survey 2<")
    source.write_text(text.replace("</trajectorys>", second.replace(old, new) + "</trajectorys>"))
    return text.count("\n")


def test_trajectories_applying_different_corrections_are_refused(tmp_path: Path):
    source = witsml(tmp_path / "grid.xml", azi_ref="grid north", head=GRID_APPLIED.format(-0.9))
    original = source.read_text()
    second_trajectory(source)
    assert gp.read(source, kind="stations").attrs["well"]["grid_convergence_applied"] == -0.9
    source.write_text(original)
    start = second_trajectory(source, GRID_APPLIED.format(-0.9), GRID_APPLIED.format(1.2))
    with pytest.raises(InputFileError, match=r"1\.2° differs from the -0\.9°") as caught:
        gp.read(source, kind="stations")  # one value in the metadata, wrong for one of them
    assert (caught.value.line, caught.value.column) == (start + 6, "gridCorUsed")


def test_magnetic_trajectories_of_different_days_are_refused(tmp_path: Path):
    """An MWD contractor's file of two runs years apart: their magnetic azimuths need each
    run's declination (one day's, the first run's, turned the other run's azimuths)."""
    source = witsml(tmp_path / "runs.xml", azi_ref="magnetic north")
    start = second_trajectory(source, "2026-03-02T08:15", "2021-06-14T10:00")
    with pytest.raises(InputFileError, match=r"2026-03-02 differs from the 2021-06-14") as caught:
        gp.read(source, kind="stations")
    assert (caught.value.line, caught.value.column) == (6, "dTimTrajStart")
    assert f"line {start + 3}" in caught.value.reason and "trajectory:" in caught.value.reason
    one = gp.read(source, kind="stations", trajectory="DEF-GYRO-2")
    assert one.attrs["well"]["survey_date"] == "2021-06-14"
    original = source.read_text()
    stated = (  # the site's declination stated: the date no longer matters
        "<commonData><extensionNameValue><name>gyropipe.well.declination</name>"
        '<value uom="dega">1.5</value></extensionNameValue></commonData>'
    )
    source.write_text(original.replace("  </trajectory>", stated + "  </trajectory>", 1))
    assert gp.read(source, kind="stations").attrs["well"]["declination"] == 1.5
    source.write_text(
        original.replace("<dTimTrajStart>2021-06-14T10:00:00.000Z</dTimTrajStart>", "")
    )
    with pytest.raises(
        InputFileError, match="without <dTimTrajStart> beside one started"
    ) as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == start


def test_true_north_trajectories_take_the_day_the_survey_began(tmp_path: Path):
    source = witsml(tmp_path / "runs.xml")
    start = second_trajectory(source, "2026-03-02T08:15", "2021-06-14T10:00")
    well = gp.read(source, kind="stations").attrs["well"]
    assert (well["survey_date"], well["survey_date_last"]) == ("2021-06-14", "2026-03-02")
    source.write_text(source.read_text().replace("2021-06-14T10:00", "2026-03-02T22:00"))
    assert "survey_date_last" not in gp.read(source, kind="stations").attrs["well"]
    lines = source.read_text().splitlines()
    del lines[start + 2]  # the second trajectory's dTimTrajStart
    source.write_text("\n".join(lines))
    with pytest.warns(InputFileWarning, match=rf"runs\.xml:{start}: trajectory without <dTim"):
        well = gp.read(source, kind="stations").attrs["well"]
    assert well["survey_date"] == "2026-03-02" and "survey_date_last" not in well


MAGNETIC = {"id": "mag", "uses": "north_reference", "with": {"target": "magnetic"}}


def test_true_north_trajectories_of_several_days_take_no_one_days_declination(tmp_path: Path):
    """Two runs a year apart turned to magnetic north: the declination of the first
    run's day (the model's at the site, 2025) is not the second's (2026); refused, not
    applied to both, unless the declination is given. The report and the exports state
    the range, not the first day."""
    source = witsml(tmp_path / "runs.xml")
    second_trajectory(source, "2026-03-02T08:15", "2025-02-10T10:00")
    pipe = survey_pipeline(tmp_path, MAGNETIC, report=True, las=False)  # two paths from 0 m
    refused = run(pipe, source, tmp_path / "refused", *WELL_ARGS)
    assert refused.returncode != 0
    assert "began on several days (2025-02-10 to 2026-03-02" in refused.output
    assert "give `declination`, or `date` (one for all)" in refused.output
    given = run(pipe, source, tmp_path / "out", *WELL_ARGS, "--set", "mag.declination=0.5")
    assert given.returncode == 0, given.output
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.column("azi").to_numpy()[-1] == pytest.approx(44.5, abs=1e-9)
    report = (tmp_path / "out" / "report.html").read_text()
    assert "2025-02-10 to 2026-03-02" in report
    traj = ET.parse(tmp_path / "out" / "trajectory.xml").getroot().findall("w:trajectory", NS)
    assert len(traj) == 2 and not any(t.find("w:dTimTrajStart", NS) is not None for t in traj)
    for export in ("trajectory.xml", "trajectory.csv"):
        back = gp.read(tmp_path / "out" / export, kind="stations").attrs["well"]
        assert (back["survey_date"], back["survey_date_last"]) == ("2025-02-10", "2026-03-02")


FIRST = "2025-02-10"


def test_a_survey_date_given_is_the_one_date(tmp_path: Path):
    """``--well survey_date=X`` over trajectories begun on several days states the one date
    to use: the file's last day goes with the file's first (once the range X…last, even
    with X after last, and no declination for it); a last day before the first is refused."""
    source = witsml(tmp_path / "runs.xml")
    second_trajectory(source, "2026-03-02T08:15", f"{FIRST}T10:00")
    pipe = survey_pipeline(tmp_path, MAGNETIC, las=False)
    for day in ("2026-03-02", "2026-06-01"):
        out = tmp_path / f"out-{day}"
        given = run(pipe, source, out, *WELL_ARGS, "--well", f"survey_date={day}")
        assert given.returncode == 0, given.output
        well = json.loads((out / "run.json").read_text())["well"]
        assert well["survey_date"] == day and "survey_date_last" not in well
        # WMM2025 at the site on that day, not on the first trajectory's (2025-02-10)
        on = {d: declination_at(*SITE.values(), dt.date.fromisoformat(d)) for d in (day, FIRST)}
        assert well["declination"] == pytest.approx(on[day], abs=1e-12) != on[FIRST]
    for args, words in [
        (["--well", "survey_date_last=2024-12-31"], "survey_date_last 2024-12-31 is before"),
        (
            ["--well", "survey_date=2026-03-02", "--well", "survey_date_last=2026-03-01"],
            "error: --well: value error, survey_date_last 2026-03-01 is before survey_date",
        ),
    ]:
        refused = run(pipe, source, tmp_path / "refused", *WELL_ARGS, *args)
        assert refused.returncode != 0
        assert words in refused.output and "Traceback" not in refused.output
    read = gp.read(source, kind="stations", well={"survey_date": "2026-06-01"})
    assert read.attrs["well"]["survey_date"] == "2026-06-01"
    assert "survey_date_last" not in read.attrs["well"]
    with pytest.raises(ValueError, match="survey_date_last 2025-01-01 is before survey_date"):
        gp.WellMetadata(survey_date=dt.date(2025, 2, 10), survey_date_last=dt.date(2025, 1, 1))


def test_a_survey_of_one_day_states_no_last_day(tmp_path: Path):
    """Its summary and pipeline digest hold no ``survey_date_last`` (as before the field)."""
    source = witsml(tmp_path / "one.xml")
    result = run(survey_pipeline(tmp_path), source, tmp_path / "out")
    assert result.returncode == 0, result.output
    well = json.loads((tmp_path / "out" / "summary.json").read_text())["well"]
    assert well["survey_date"] == "2026-03-02" and "survey_date_last" not in well
    spec = load_spec(survey_pipeline(tmp_path)).spec  # what its digest is of
    assert "survey_date_last" not in spec.model_dump(mode="json")["well"]


def test_a_magnetic_tool_model_takes_no_one_days_field_for_several_days(tmp_path: Path):
    source = witsml(tmp_path / "runs.xml")
    second_trajectory(source, "2026-03-02T08:15", "2025-02-10T10:00")
    mwd = {"id": "mwd", "uses": "position_uncertainty", "with": {"model": "ISCWSA-MWD-REV5"}}
    pipe = survey_pipeline(tmp_path, las=False)
    spec = yaml.safe_load(pipe.read_text())
    spec["stages"].append({**mwd, "inputs": {"trajectory": "trajectory.trajectory"}})
    pipe.write_text(yaml.safe_dump(spec, sort_keys=False))
    with pytest.raises(gp.GyropipeError, match="began on several days") as caught:
        gp.run(pipe, {"stations": source}, well=SITE, out=tmp_path / "refused")
    assert "`magnetic_field`, `magnetic_dip` and `declination`" in str(caught.value)
    field = {"magnetic_field": 50_000.0, "magnetic_dip": 71.0, "declination": 0.5}
    result = gp.run(pipe, {"stations": source}, well=SITE | field, out=tmp_path / "out")
    assert result.tables["mwd.trajectory"].column("ellipse_major").to_numpy()[-1] > 1.0


def test_trajectories_measured_from_two_datums_are_refused(tmp_path: Path):
    """An operator's store: the drilling rig's trajectory from its DF, a later run from the
    workover rig's KB, metres apart: one survey of them is offset by the difference."""
    source = witsml(tmp_path / "rigs.xml")
    source.write_text(source.read_text().replace('<md uom="m">', '<md uom="m" datum="DF">'))
    start = second_trajectory(source, 'datum="DF"', 'datum="KB"')
    with pytest.raises(InputFileError, match="datum 'KB' differs from the 'DF' at line 11") as e:
        gp.read(source, kind="stations")
    assert (e.value.line, e.value.column) == (start + 8, "md")  # the copy's first station
    one = gp.read(source, kind="stations", trajectory="DEF-GYRO-2")
    assert one["md"].iloc[-1] == Survey().md[-1]


def test_a_trajectory_without_azimuth_reference_does_not_take_anothers(tmp_path: Path):
    source = witsml(tmp_path / "two.xml", azi_ref="grid north")
    start = second_trajectory(source, "<aziRef>grid north</aziRef>", "")
    with pytest.raises(InputFileError, match="absent or 'unknown' here but 'grid north'") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == start
    stations = gp.read(source, kind="stations", north_reference="grid")
    assert stations.attrs["north_reference"] == "grid"
    assert stations["survey"].nunique() == 2


def test_grid_north_exports_keep_their_applied_convergence_for_magnetic_models(tmp_path: Path):
    g = gamma()
    survey = Survey()
    grid_azi = {k: repr(math.radians((45.0 - g) % 360.0)) for k in range(1, survey.md.size)}
    source = witsml(
        tmp_path / "grid.xml",
        azi_ref="grid north",
        head=f'<gridCorUsed uom="dega">{g!r}</gridCorUsed>',
        azi_rad={k: v for k, v in grid_azi.items() if survey.inc[k] > 0},
        grid_gamma=g,
    )
    mwd = {"id": "mwd", "uses": "position_uncertainty", "with": {"model": "ISCWSA-MWD-REV5"}}
    pipe = survey_pipeline(tmp_path, las=False)
    spec = yaml.safe_load(pipe.read_text())
    spec["stages"].append({**mwd, "inputs": {"trajectory": "trajectory.trajectory"}})
    pipe.write_text(yaml.safe_dump(spec, sort_keys=False))
    with warnings.catch_warnings():  # the listing's grid-frame positions agree with its angles
        warnings.simplefilter("error", SurveyCheckWarning)
        result = gp.run(pipe, {"stations": source}, well=SITE, out=tmp_path / "out")
    assert result.well.grid_convergence_applied == g and result.well.grid_convergence is None
    assert result.tables["mwd.trajectory"].column("ellipse_major").to_numpy()[-1] > 1.0


# --------------------------------------------------------------------------- 2. null markers

STATIONS_CSV = "MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n100,5,45\n200,10,{azi}\n300,12,46\n"


@pytest.mark.parametrize("marker", ["-999.25", "999.25", "-9999.25"])
def test_a_null_marker_azimuth_is_a_located_error(tmp_path: Path, marker: str):
    source = tmp_path / "stations.csv"
    source.write_text(STATIONS_CSV.format(azi=marker))
    result = run(survey_pipeline(tmp_path), source, tmp_path / "out")
    assert result.returncode != 0
    assert f"{source}:4" in result.output and "azi" in result.output
    with pytest.raises(InputFileError) as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 4


def test_csv_and_las_stations_missing_an_angle_are_left_out_when_asked(tmp_path: Path):
    source = tmp_path / "stations.csv"
    source.write_text(STATIONS_CSV.format(azi="-999.25").replace("100,5,45", "100,-999.25,45"))
    refused = run(survey_pipeline(tmp_path), source, tmp_path / "refused")
    assert refused.returncode != 0
    assert f"{source}:3" in refused.output and "null_stations: drop" in refused.output
    drop = ["--set", "read.options={null_stations: drop}"]
    dropped = run(survey_pipeline(tmp_path), source, tmp_path / "out", *drop)
    assert dropped.returncode == 0, dropped.output
    assert re.search(r"warning: .*2 station\(s\) .* left out .*; lines 3, 4", dropped.stderr)
    md = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet").column("md")
    assert md.to_pylist() == [0.0, 300.0]
    source.write_text(STATIONS_CSV.format(azi="46").replace("100,5,45", "100,,45"))  # empty
    with pytest.warns(InputFileWarning, match=r"1 station\(s\) .* left out"):
        kept = gp.read(source, kind="stations", null_stations="drop")
    assert kept.md.tolist() == [0.0, 200.0, 300.0]
    las = tmp_path / "stations.las"  # NULL -999.25; a 999.25 azimuth is a null marker too
    las.write_text(
        "~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n NULL. -999.25 :\n WELL. W :\n"
        "~Curve\n DEPT.m : md\n INC.deg : inc\n AZI.deg : azimuth\n~Parameter\n"
        " NREF. true :\n~A\n0 0 0\n100 5 999.25\n200 10 46\n"
    )
    with pytest.raises(InputFileError, match=r"station at md 100\.0 has no azimuth") as caught:
        gp.read(las, kind="stations")
    assert (caught.value.line, caught.value.column) == (15, "azi")
    with pytest.warns(InputFileWarning, match="left out"):
        assert gp.read(las, kind="stations", null_stations="drop").md.tolist() == [0.0, 200.0]


def test_a_null_marker_witsml_azimuth_is_an_error_or_a_dropped_station(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml", azi_rad={40: "999.25"})
    pipe = survey_pipeline(tmp_path)
    refused = run(pipe, source, tmp_path / "refused")
    assert refused.returncode != 0
    assert "<azi> 999.25 is a null marker" in refused.output
    assert "null_stations: drop" in refused.output
    line = next(i for i, t in enumerate(source.read_text().splitlines(), 1) if 'uid="s40"' in t)
    assert f"{source}:{line}" in refused.output
    dropped = run(pipe, source, tmp_path / "out", "--set", "read.options={null_stations: drop}")
    assert dropped.returncode == 0, dropped.output
    left_out = rf"vendor\.xml:{line}: 1 station\(s\) without inclination or azimuth left out"
    assert re.search(rf"warning: .*{left_out}", dropped.stderr), dropped.stderr
    md = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet").column("md")
    assert md.to_pylist() == [m for k, m in enumerate(Survey().md.tolist()) if k != 40]


def test_null_markers_in_the_station_corrections_are_no_values(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml", head="")  # stn…Used: ±999.25 rad on every station
    well = gp.read(source, kind="stations").attrs["well"]
    assert "grid_convergence_applied" not in well and "declination_applied" not in well
    stated = witsml(tmp_path / "stated.xml")  # and gridCorUsed 0 above them: no conflict
    assert gp.read(stated, kind="stations").attrs["well"]["grid_convergence_applied"] == 0.0


# ----------------------------------------------------------------------- 3. plausible angles


@pytest.mark.parametrize(("azi", "line"), [("800", 4), ("-400", 4)])
def test_an_azimuth_out_of_range_is_never_wrapped(tmp_path: Path, azi: str, line: int):
    source = tmp_path / "stations.csv"
    source.write_text(STATIONS_CSV.format(azi=azi))
    with pytest.raises(InputFileError, match=r"azimuth .* is outside \[-360, 720\)") as caught:
        gp.read(source, kind="stations")
    assert (caught.value.line, caught.value.column) == (line, "azi")


def test_an_azimuth_past_360_is_read_with_a_warning(tmp_path: Path):
    source = tmp_path / "stations.csv"
    source.write_text(STATIONS_CSV.format(azi="400"))
    said = r"stations\.csv:4: azi 400\.0° read as 40\.0°, the same direction \(an azimuth in"
    with pytest.warns(InputFileWarning, match=said):
        gp.read(source, kind="stations")
    result = run(survey_pipeline(tmp_path), source, tmp_path / "out")  # the CLI says it too
    assert (
        result.returncode == 0 and "wrapped into [0, 360), one outside it refused" in result.stderr
    )


def _radian_csv(path: Path, unit: str, scale: float) -> Path:
    survey = Survey()
    rows = [
        f"{float(m)!r},{float(i * scale)!r},{float(a * scale)!r}"
        for m, i, a in zip(survey.md, survey.inc, survey.azi, strict=True)
    ]
    path.write_text(f"MD (m),Inc ({unit}),Azimuth True ({unit})\n" + "\n".join(rows) + "\n")
    return path


def test_radians_declared_degrees_are_refused_unless_confirmed(tmp_path: Path):
    source = _radian_csv(tmp_path / "rad.csv", "deg", math.pi / 180.0)  # 3,510 m, max 0.70
    pipe = survey_pipeline(tmp_path)
    refused = run(pipe, source, tmp_path / "refused")
    assert refused.returncode != 0
    assert "inc and azi look like radians read as degrees" in refused.output
    assert "angle_unit_confirmed" in refused.output
    confirmed = run(
        pipe, source, tmp_path / "out", "--set", "read.options={angle_unit_confirmed: true}"
    )
    assert confirmed.returncode == 0, confirmed.output
    vendor = witsml(tmp_path / "vendor.xml", angle_uom="dega")  # radian numbers declared dega
    with pytest.raises(InputFileError, match="look like radians read as degrees"):
        gp.read(vendor, kind="stations")


def test_degrees_declared_radians_name_the_likely_unit(tmp_path: Path):
    source = _radian_csv(tmp_path / "deg.csv", "rad", 1.0)
    with pytest.raises(InputFileError, match="looks like degrees declared as radians") as caught:
        gp.read(source, kind="stations")
    assert caught.value.column in ("inc", "azi") and caught.value.line > 1


# ------------------------------------------------------------------------- 4. the survey tool


def test_the_survey_tool_reaches_the_exports_and_the_report(tmp_path: Path):
    source = witsml(tmp_path / "vendor.xml")  # the tie-in station names no tool
    result = run(survey_pipeline(tmp_path, report=True), source, tmp_path / "out")
    assert result.returncode == 0, result.output
    stations = trajectory_xml(tmp_path / "out").findall("w:trajectoryStation", NS)
    tools = {s.findtext("w:typeSurveyTool", namespaces=NS) for s in stations}
    assert tools == {"gyroscopic north seeking"}
    kinds = [s.findtext("w:typeTrajStation", namespaces=NS) for s in stations]
    assert kinds[0] == "tie in point" and set(kinds[1:]) == {"gyro north seeking"}
    assert las_params(tmp_path / "out").get("TOOL") is None  # TOOL is a ~Well item
    tool = lasio.read(str(tmp_path / "out" / "trajectory.las")).well["TOOL"].value
    assert tool == "gyroscopic north seeking"
    assert "gyroscopic north seeking" in (tmp_path / "out" / "report.html").read_text()


# ------------------------------------------------------------------- 5. units of the header


def title_csv(path: Path, title: str, header: str = "MD (ft),Inc (deg),Azimuth True (deg)") -> Path:
    """A listing of three stations under ``header`` (an extra column: TVD), below ``title``."""
    tvd = "TVD" in header
    rows = [(0, 0, 0, 0), (1000, 5, 45, 300), (2000, 10, 46, 600)]
    body = "".join(",".join(map(str, row if tvd else row[:3])) + "\n" for row in rows)
    path.write_text(f"Well: A-7\n{title}\n\n{header}\n{body}")
    return path


def test_a_unitless_elevation_is_in_the_files_length_unit(tmp_path: Path):
    """A listing in feet writes its elevation in feet without saying so (82 ft, not 82 m
    above sea level in the report and the exports)."""
    source = title_csv(tmp_path / "feet.csv", "Elevation: 82")
    result = run(survey_pipeline(tmp_path), source, tmp_path / "out")
    assert result.returncode == 0, result.output
    entries = ET.parse(tmp_path / "out" / "trajectory.xml").iter(f"{{{NS['w']}}}extensionNameValue")
    stated = {e.findtext("w:name", namespaces=NS): e.find("w:value", NS) for e in entries}
    value = stated["gyropipe.well.elevation"]
    assert value is not None and value.attrib["uom"] == "m"
    assert float(value.text or "") == pytest.approx(82 * 0.3048, abs=1e-12)
    metres = title_csv(tmp_path / "m.csv", "Elevation: 54.3", "MD (m),Inc (deg),Azimuth True (deg)")
    assert gp.read(metres, kind="stations").attrs["well"]["elevation"] == 54.3
    ours = title_csv(tmp_path / "ours.csv", "# well.elevation=24.9936")  # gyropipe's field, m
    assert gp.read(ours, kind="stations").attrs["well"]["elevation"] == 24.9936


def test_a_unitless_elevation_beside_two_length_units_is_refused(tmp_path: Path):
    header = "MD (ft),Inc (deg),Azimuth True (deg),TVD (m)"
    source = title_csv(tmp_path / "mixed.csv", "Elevation: 82", header)
    with pytest.raises(
        InputFileError, match=r"elevation '82': no unit.*'MD \(ft\)' in ft"
    ) as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 2
    feet = gp.read(source, kind="stations", units={"tvd": "ft"}).attrs["well"]["elevation"]
    assert feet == pytest.approx(82 * 0.3048, abs=1e-12)


def test_a_unitless_las_elevation_is_in_the_files_depth_unit(tmp_path: Path):
    source = tmp_path / "feet.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.F 0 :\n STOP.F 2000 :\n STEP.F 1000 :\n NULL. -999.25 :\n NREF. TRUE :\n"
        " EKB.  82 : kelly bushing elevation\n"
        "~Curve\n DEPT.F : measured depth\n INC.DEG : inclination\n AZI.DEG : azimuth\n"
        "~A\n0 0 0\n1000 10 45\n2000 20 45\n"
    )
    well = gp.read(source, kind="stations").attrs["well"]
    assert (well["elevation"], well["depth_reference"]) == (pytest.approx(82 * 0.3048), "KB")
    source.write_text(source.read_text().replace(" STEP.F", " STEP.M"))
    with pytest.raises(InputFileError, match="EKB: no unit, and the depths") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 10


def test_a_unitless_las_elevation_follows_the_units_option(tmp_path: Path):
    """A file mislabelled DEPT.M whose depths are feet (``units: {md: ft}``): its bare EKB is
    in the same feet, not in the metres of the label (82 m above sea level in the exports);
    depths with no unit but the option's give it too (the EKB was refused)."""
    source = tmp_path / "mislabelled.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.M 0 :\n STOP.M 2000 :\n STEP.M 1000 :\n NULL. -999.25 :\n NREF. TRUE :\n"
        " EKB.  82 : kelly bushing elevation\n"
        "~Curve\n DEPT.M : measured depth\n INC.DEG : inclination\n AZI.DEG : azimuth\n"
        "~A\n0 0 0\n1000 10 45\n2000 20 45\n"
    )
    stations = gp.read(source, kind="stations", units={"md": "ft"})
    assert stations["md"].tolist() == [0.0, 304.8, 609.6]
    assert stations.attrs["well"]["elevation"] == pytest.approx(82 * 0.3048, abs=1e-12)
    assert gp.read(source, kind="stations").attrs["well"]["elevation"] == 82.0
    source.write_text(source.read_text().replace(".M ", ". "))  # no depth unit but the option's
    feet = gp.read(source, kind="stations", units={"md": "ft"}).attrs["well"]["elevation"]
    assert feet == pytest.approx(82 * 0.3048, abs=1e-12)


def test_us_survey_feet_in_the_energistics_spelling_are_read(tmp_path: Path):
    """Petrel and other Energistics-minded tools write the US survey foot as ftUS."""
    header = "MD (ftUS),Inc (deg),Azimuth True (deg)"
    source = title_csv(tmp_path / "usft.csv", "Elevation: 82", header)
    stations = gp.read(source, kind="stations")
    assert stations["md"].tolist() == [0.0, 1000 * 1200 / 3937, 2000 * 1200 / 3937]
    assert stations.attrs["well"]["elevation"] == pytest.approx(82 * 1200 / 3937, abs=1e-12)


@pytest.mark.parametrize("date", ["21-Nov-2026", "Nov 21, 2026", "21/11/2026", "20261121"])
def test_a_csv_title_date_is_read_as_a_las_date_is(tmp_path: Path, date: str):
    """Vendors' listings date the survey as their LAS files do, not only in ISO form."""
    source = title_csv(tmp_path / "dated.csv", f"Survey Date: {date}")
    assert gp.read(source, kind="stations").attrs["well"]["survey_date"] == "2026-11-21"


@pytest.mark.parametrize(
    ("item", "field"),
    [
        ("EKB.F  -999.25 : kelly bushing elevation", "elevation"),
        ("EKB.F  -9999 : kelly bushing elevation", "elevation"),  # the file's NULL
        ("LATI.DEG  -999.25 : latitude", "latitude"),
        ("DECL.DEG  999.25 : declination", "declination"),
    ],
)
def test_a_null_in_a_las_header_item_is_no_value(tmp_path: Path, item: str, field: str):
    """Vendors fill the header items they do not know with the file's NULL, as in the data:
    an elevation of -999.25 m went into the report and the exports."""
    source = tmp_path / "nulls.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.M 0 :\n STOP.M 200 :\n STEP.M 100 :\n NULL. -9999 :\n NREF. TRUE :\n"
        f" {item}\n"
        "~Curve\n DEPT.M : measured depth\n INC.DEG : inclination\n AZI.DEG : azimuth\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    result = run(survey_pipeline(tmp_path), source, tmp_path / "out")
    assert result.returncode == 0, result.output
    entries = ET.parse(tmp_path / "out" / "trajectory.xml").iter(f"{{{NS['w']}}}extensionNameValue")
    assert f"gyropipe.well.{field}" not in {e.findtext("w:name", namespaces=NS) for e in entries}
    assert field not in gp.read(source, kind="stations").attrs["well"]


def test_a_null_in_a_csv_title_is_no_value(tmp_path: Path):
    source = title_csv(tmp_path / "nulls.csv", "Elevation: -999.25\nDeclination: -999.25 deg")
    assert gp.read(source, kind="stations").attrs["well"] == {
        "well": "A-7",
        "north_reference": "true",
    }


NO_NORTH = "no north reference for the azimuths"
AMBIGUOUS = "ambiguous north reference"


@pytest.mark.parametrize(
    ("description", "refusal"),
    [
        ("Azimuth, not grid corrected", NO_NORTH),
        ("Azimuth, mag dec applied", NO_NORTH),
        ("Azimuth (no grid correction)", NO_NORTH),
        ("Azimuth (mag corrected)", AMBIGUOUS),
        ("Magnetic corrected azimuth", AMBIGUOUS),
    ],
)
def test_a_las_description_naming_a_correction_names_no_north(
    tmp_path: Path, description: str, refusal: str
):
    """A vendor's words about what was (not) applied are no north reference: read as one,
    these were grid and magnetic azimuths, wrong by the convergence or the declination.
    'mag corrected' was read as magnetic north; vendors write it of azimuths turned to true
    north (declination applied) and of magnetic ones corrected for drillstring
    interference. Refused at the curve's line; read once NREF or the option names it."""
    source = tmp_path / "said.las"
    source.write_text(
        "~Version\n VERS.  2.0 : LAS\n WRAP.  NO :\n"
        "~Well\n STRT.M 0 :\n STOP.M 200 :\n STEP.M 100 :\n NULL. -999.25 :\n"
        f"~Curve\n DEPT.M : measured depth\n INC.DEG : inclination\n AZI.DEG : {description}\n"
        "~A\n0 0 0\n100 10 45\n200 20 45\n"
    )
    with pytest.raises(InputFileError, match=refusal) as caught:
        gp.read(source, kind="stations")
    assert (caught.value.line, caught.value.column) == (12, "AZI")
    read = gp.read(source, kind="stations", north_reference="magnetic")
    assert read.attrs["north_reference"] == "magnetic"
    source.write_text(source.read_text().replace(" NULL.", " NREF. TRUE :\n NULL."))
    assert gp.read(source, kind="stations").attrs["north_reference"] == "true"
    source.write_text(source.read_text().replace(" NULL.", " NREF. TRUE :\n NULL."))
    assert gp.read(source, kind="stations").attrs["north_reference"] == "true"
