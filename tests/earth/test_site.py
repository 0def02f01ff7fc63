"""Where a stage finds the site (:func:`pipeline.earth.site.resolve_site`): its own parameter
before the well metadata; and, through the CLI, the one-line error (exit 1) of every stage
that needs the site when neither gives the latitude."""

from __future__ import annotations

import datetime as dt
import textwrap
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from pydantic import ValidationError

from pipeline.earth.site import Site, SiteParams, resolve_site
from pipeline.errors import GyropipeError, MissingSiteError
from pipeline.stages.uncertainty import UncertaintyParams
from pipeline.well import WellMetadata, attach, well_of
from tests_support import ROOT, gyropipe_cli

WELL = WellMetadata(
    latitude=61.25, longitude=73.4, elevation=54.3, survey_date=dt.date(2026, 11, 21)
)


def test_the_stage_parameter_beats_the_well_metadata() -> None:
    site = resolve_site(WELL, stage="compass", latitude=-33.9)
    assert site.latitude == -33.9
    assert (site.longitude, site.elevation, site.date) == (73.4, 54.3, dt.date(2026, 11, 21))
    assert resolve_site(WELL, stage="compass").latitude == 61.25
    assert resolve_site(WellMetadata(), stage="compass", latitude=10.0).latitude == 10.0
    bare = resolve_site(WellMetadata(latitude=5.0), stage="compass")
    assert (bare.longitude, bare.elevation, bare.date) == (0.0, 0.0, None)


def test_one_latitude_type_bounds_every_latitude() -> None:
    """The well's, the site's and every stage's latitude are one type: −90…90°, finite."""
    for make in (
        lambda v: WellMetadata(latitude=v),
        lambda v: Site(latitude=v),
        lambda v: SiteParams(latitude=v),
        lambda v: UncertaintyParams(latitude=v),
    ):
        assert make(-90.0).latitude == -90.0 and make(90.0).latitude == 90.0
        for bad, why in ((90.5, "less than or equal to 90"), (float("nan"), "finite number")):
            with pytest.raises(ValidationError, match=why):
                make(bad)


def test_a_north_seeking_stage_refuses_a_latitude_at_a_pole() -> None:
    polar = WellMetadata(latitude=89.95)
    assert resolve_site(polar, stage="validity").latitude == 89.95
    with pytest.raises(ValueError, match=r"latitude 89\.95° is beyond ±89\.9°: a north-seeking"):
        resolve_site(polar, stage="compass", north_seeking=True)
    with pytest.raises(ValueError, match="latitude -90° is beyond"):
        resolve_site(WELL, stage="compass", latitude=-90.0, north_seeking=True)


def test_missing_values_are_named_with_where_to_give_them() -> None:
    with pytest.raises(MissingSiteError) as info:
        resolve_site(WellMetadata(longitude=73.4), stage="compass")
    assert isinstance(info.value, GyropipeError)
    assert str(info.value) == (
        "the compass stage needs the site latitude: set the compass stage's `latitude`, or "
        "the well's `latitude` in the pipeline's `well:` block, on the command line "
        "(--well latitude=…) or in the input file's header"
    )
    with pytest.raises(MissingSiteError) as info:  # a geomagnetic model needs more
        resolve_site(WellMetadata(latitude=61.25), stage="validity_checks", param=None, field=True)
    assert info.value.missing == ["longitude", "survey_date"]
    assert str(info.value).startswith(
        "the validity_checks stage needs the site longitude and survey_date (for the "
        "geomagnetic model): set the well's `longitude` and `survey_date` in"
    )
    assert resolve_site(WELL, stage="validity_checks", field=True).date == WELL.survey_date


def test_a_python_function_names_its_own_arguments() -> None:
    """Issue 28 item 13: in Python the message spoke of ``--well``; it names the function's
    ``latitude=`` argument and ``well=``, and the argument it names works."""
    import pipeline as gp

    readings = gp.read(ROOT / "examples" / "readings-j-well.csv", kind="readings")
    with pytest.raises(GyropipeError) as info:
        gp.compass(readings, well={"latitude": None})
    assert str(info.value).endswith(
        "the compass stage needs the site latitude: give the function's `latitude=` argument "
        'or `well={"latitude": …}` (or the input\'s well metadata)'
    )
    assert "--well" not in str(info.value)
    assert len(gp.compass(readings, latitude=61.25).stations) > 0


SIM_PLAN = """
name: no-latitude
seed: 3
site: {latitude: 61.25, longitude: 73.4, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 30}
    - {kind: build, dls: 9.0, inc: 30, azi: 37}
tool: {preset: mems-vrg}
survey: {mode: point, every: 30, dwell: 20, move_time: 2}
"""

READ = {
    "samples": "  - {id: read, uses: read_samples}",
    "readings": "  - {id: read, uses: read_readings}",
    "stations": "  - {id: read, uses: read_stations}",
}
CASES = {  # stage → (input kind, the pipeline's stages after the reader)
    "compass": ("readings", "  - {id: stage, uses: compass, inputs: {readings: read.readings}}"),
    "validity_checks": (
        "readings",
        "  - {id: stage, uses: validity_checks, inputs: {readings: read.readings}}",
    ),
    "window_checks": (
        "samples",
        "  - {id: stage, uses: window_checks, inputs: {samples: read.samples}}",
    ),
    "allan": ("samples", "  - {id: stage, uses: allan, inputs: {samples: read.samples}}"),
    "integrate_continuous": (  # the compass stage's own latitude is not the next stage's
        "samples",
        """\
  - {id: readings, uses: position_readings, inputs: {samples: read.samples}}
  - id: stops
    uses: compass
    inputs: {readings: readings.readings}
    with: {latitude: 61.25}
  - id: stage
    uses: integrate_continuous
    inputs: {samples: read.samples, stops: stops.stations}""",
    ),
    "position_uncertainty": (
        "stations",
        """\
  - {id: trajectory, uses: minimum_curvature, inputs: {stations: read.stations}}
  - {id: stage, uses: position_uncertainty, inputs: {trajectory: trajectory.trajectory}}""",
    ),
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One input file of each kind, its header without the latitude (the rest is kept)."""
    root = tmp_path_factory.mktemp("site")
    (root / "plan.yaml").write_text(SIM_PLAN)
    gyropipe_cli("simulate", str(root / "plan.yaml"), "--out", str(root / "sim"), check=True)
    samples = pq.read_table(root / "sim" / "samples.parquet")
    known = well_of(samples)
    assert known is not None and known.latitude == 61.25
    unset = known.model_dump(exclude_unset=True, exclude={"latitude"})
    pq.write_table(attach(samples, WellMetadata.model_validate(unset)), root / "samples.parquet")
    files = {"samples": root / "samples.parquet"}
    for kind, source, line in (
        ("readings", "readings-j-well.csv", "# well.latitude=61.25\n"),
        ("stations", "stations-j-well.csv", "Latitude: 61.25\n"),
    ):
        text = (ROOT / "examples" / source).read_text()
        assert line in text
        files[kind] = root / source
        files[kind].write_text(text.replace(line, ""))
    return files


@pytest.mark.parametrize("stage", list(CASES))
def test_a_stage_without_a_latitude_fails_in_one_line(
    stage: str, inputs: dict[str, Path], tmp_path: Path
) -> None:
    kind, stages = CASES[stage]
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(
        textwrap.dedent(
            f"""\
            name: needs-site
            version: "1.0"
            inputs:
              {kind}: {{description: the input without a latitude}}
            stages:
            """
        )
        + READ[kind]
        + "\n"
        + stages
        + "\n"
    )
    out = tmp_path / "out"
    result = gyropipe_cli("run", str(pipeline), "--input", str(inputs[kind]), "--out", str(out))
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    (line,) = [text for text in result.stderr.splitlines() if text.startswith("error:")]
    given = "" if stage.endswith("_checks") else f"the {stage} stage's `latitude`, or "
    assert line.startswith(f"error: stage 'stage' ({stage} from plugin ")
    assert line.endswith(
        f"failed: MissingSiteError: the {stage} stage needs the site latitude: set {given}the "
        "well's `latitude` in the pipeline's `well:` block, on the command line "
        "(--well latitude=…) or in the input file's header"
    )
    assert not (out / "run.json").exists()
