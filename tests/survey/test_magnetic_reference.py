"""No example constants in shipped pipelines (issue 28, item 6): the geomagnetic reference
of MWD models comes from the well metadata or the geomagnetic model at the well's site and
date, is refused when neither is there, and the report's method states every value applied
with its source."""

from __future__ import annotations

import datetime as dt
import html
import re
from pathlib import Path

import pytest

import pipeline as gp
from pipeline.earth.geomagnetic import reference_field
from pipeline.stages.uncertainty import magnetic_of
from tests_support import ROOT, CliResult, gyropipe_cli

DEFINITIVE = ROOT / "pipelines" / "definitive.yaml"
CLEARANCE = ROOT / "pipelines" / "clearance.yaml"
RUNS = ROOT / "examples" / "definitive"
ISCWSA = ROOT / "examples" / "clearance"
SITE = ("Latitude:", "Longitude:", "Survey Date:", "Elevation:", "Magnetic")


def method_text(report: Path) -> str:
    """The report's method section as plain text."""
    text = report.read_text()
    section = re.search(r'id="method".*?(?=<section|</main)', text, re.S)
    assert section, "no method section"
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", section.group(0))).split())


def definitive(
    out: Path, *args: str, gyro: Path = RUNS / "gyro-run.csv", mwd: Path = RUNS / "mwd-run.csv"
) -> CliResult:
    return gyropipe_cli(
        "run",
        DEFINITIVE,
        "--input",
        f"gyro={gyro}",
        "--input",
        f"mwd={mwd}",
        "--out",
        out,
        "--set",
        "report.formats=[html]",
        *args,
    )


def without_site(source: Path, directory: Path) -> Path:
    """``source`` without the header lines that give the site, date or field."""
    kept = [line for line in source.read_text().splitlines() if not line.startswith(SITE)]
    path = directory / source.name
    path.write_text("\n".join(kept) + "\n")
    return path


def test_definitive_applies_the_model_at_the_site_and_says_so(tmp_path: Path) -> None:
    result = definitive(tmp_path / "out")
    assert result.returncode == 0, result.output
    wmm = reference_field(61.25, 73.4, 54.3, dt.date(2026, 11, 21)).reference()
    assert (
        f"geomagnetic reference: total field {wmm.total_field:,.0f} nT, dip {wmm.dip:.2f}°, "
        f"declination {wmm.declination:.2f}° (WMM2025 at 61.2500° N 73.4000° E, 2026-11-21)"
    ) in method_text(tmp_path / "out" / "report.html")


def test_definitive_applies_the_wells_own_field(tmp_path: Path) -> None:
    given = [
        "--well",
        "magnetic_field=51000",
        "--well",
        "magnetic_dip=71.5",
        "--well",
        "declination=2.5",
    ]
    result = definitive(tmp_path / "given", *given)
    assert result.returncode == 0, result.output
    assert (
        "geomagnetic reference: total field 51,000 nT, dip 71.50°, declination 2.50° (given in "
        "the well metadata)"
    ) in method_text(tmp_path / "given" / "report.html")

    # the API: the field is applied (the MWD ellipses change with it), and recorded
    inputs = {"gyro": RUNS / "gyro-run.csv", "mwd": RUNS / "mwd-run.csv"}
    ours = gp.run(
        DEFINITIVE, inputs, well={"magnetic_field": 51000, "magnetic_dip": 71.5, "declination": 2.5}
    )
    modelled = gp.run(DEFINITIVE, inputs)
    applied = magnetic_of(ours.tables["definitive.survey"])
    assert applied is not None and applied.field_source == "given in the well metadata"
    assert (applied.reference.total_field, applied.reference.dip) == (51000.0, 71.5)
    major = ours.frame("definitive.survey")["ellipse_major"].iloc[-1]
    assert major != pytest.approx(modelled.frame("definitive.survey")["ellipse_major"].iloc[-1])


def test_definitive_without_a_site_or_a_field_is_refused(tmp_path: Path) -> None:
    gyro = without_site(RUNS / "gyro-run.csv", tmp_path)
    mwd = without_site(RUNS / "mwd-run.csv", tmp_path)
    result = definitive(tmp_path / "out", "--well", "latitude=61.25", gyro=gyro, mwd=mwd)
    assert result.returncode == 1
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in result.output
    assert "the definitive_survey stage needs the geomagnetic reference" in errors[0]
    assert "missing: `longitude`, `survey_date`" in errors[0] and "magnetic_field" in errors[0]
    assert not (tmp_path / "out").exists()
    with pytest.raises(gp.GyropipeError, match="needs the geomagnetic reference"):
        gp.run(DEFINITIVE, {"gyro": gyro, "mwd": mwd}, well={"latitude": 61.25})


def clearance(out: Path, reference: Path, *args: str) -> CliResult:
    return gyropipe_cli(
        "run",
        CLEARANCE,
        "--input",
        f"reference={reference}",
        "--input",
        f"offsets={ISCWSA / 'manifest.csv'}",
        "--set",
        "clearance.reference_model=ISCWSA-MWD-REV4",
        "--set",
        "clearance.reference_hole_diameter=0.9144",
        "--set",
        "report.formats=[html]",
        "--out",
        out,
        *args,
    )


def test_clearance_states_the_field_the_iscwsa_example_gives(tmp_path: Path) -> None:
    result = clearance(tmp_path / "set", ISCWSA / "reference.csv")
    assert result.returncode == 0, result.output
    assert (
        "Geomagnetic reference (clearance) total field 50,000 nT, dip 70.00°, declination "
        "0.00° (given in the well metadata)"
    ) in method_text(tmp_path / "set" / "report.html")

    # a well without its own field: WMM2025 at its site (on a date the model covers), its
    # declination still its own
    lines = (ISCWSA / "reference.csv").read_text().splitlines()
    own = tmp_path / "reference.csv"
    own.write_text("\n".join(x for x in lines if not x.startswith("Magnetic")) + "\n")
    result = clearance(tmp_path / "wmm", own, "--well", "survey_date=2026-06-01")
    assert result.returncode == 0, result.output
    wmm = reference_field(60.0, 0.0098, 0.0, dt.date(2026, 6, 1)).reference()
    assert (
        f"total field {wmm.total_field:,.0f} nT, dip {wmm.dip:.2f}° (WMM2025 at 60.0000° N "
        "0.0098° E, 2026-06-01), declination 0.00° (given in the well metadata)"
    ) in method_text(tmp_path / "wmm" / "report.html")


def test_no_shipped_pipeline_carries_a_field_or_a_hole() -> None:
    for path in (DEFINITIVE, CLEARANCE):
        text = "\n".join(line.split("#", 1)[0] for line in path.read_text().splitlines())
        assert "magnetic:" not in text and "total_field" not in text, path
    assert "reference_hole_diameter:" not in "\n".join(
        line.split("#", 1)[0] for line in CLEARANCE.read_text().splitlines()
    )
    result = gyropipe_cli("validate", CLEARANCE)
    assert result.returncode == 2 and "reference_hole_diameter" in result.stderr
