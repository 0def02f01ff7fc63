"""A WITSML 2.0 ``Trajectory`` (as a store exports it: one object per document, its name in
``eml:Citation``, elements in schema order, ``uom`` per measure) is read by the rules of the
1.4.1.1 reader: units, north, the corrections applied, station status and type. 2.0 types a
normal survey station ``MD INCL and AZI`` and names its tool in ``TypeSurveyTool``; an
inclination-only station (``MD and INCL``) or an interpolated one is no measured direction
and is left out with a warning at its line. WITSML 2.1 is refused."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import pytest
from vendor_exports import survey_pipeline

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning
from tests_support import gyropipe_cli

FT = 0.3048
HEAD = """\
<?xml version="1.0" encoding="utf-8"?>
<Trajectory xmlns="http://www.energistics.org/energyml/data/witsmlv2" \
xmlns:eml="http://www.energistics.org/energyml/data/commonv2" \
uuid="6f1c6a3e-2f0a-4b1e-9d3c-0f4c2c8e5a11" schemaVersion="{version}">
  <eml:Citation>
    <eml:Title>Gyro survey 12 1/4 in</eml:Title>
    <eml:Originator>Example Survey Co</eml:Originator>
    <eml:Creation>2026-03-02T10:00:00Z</eml:Creation>
    <eml:Format>Example Store 4.2</eml:Format>
  </eml:Citation>
  <eml:ExtensionNameValue><eml:Name>gyropipe.well.latitude</eml:Name>\
<eml:Value uom="dega">61.25</eml:Value></eml:ExtensionNameValue>
  <GrowingStatus>{growing}</GrowingStatus>
  <DTimTrajStart>2026-03-02T06:00:00Z</DTimTrajStart>
  <MdMn uom="ft" datum="KB">0</MdMn>
  <MdMx uom="ft" datum="KB">1200</MdMx>
  <ServiceCompany>Example Survey Co</ServiceCompany>
  <GridConUsed uom="dega">1.25</GridConUsed>
  <AziRef>grid north</AziRef>
"""
STATIONS = [
    ("tie in point", None, 0.0, 0.0, 0.0),
    ("MD INCL and AZI", "gyroscopic north seeking", 1000.0, 0.0, 0.0),
    ("MD INCL and AZI", "gyroscopic north seeking", 1100.0, 3.0, 127.5),
    ("MD INCL and AZI", "gyroscopic north seeking", 1200.0, 6.0, 127.5),
]
"""type, tool, md (ft), incl, azi (deg, grid north)"""
TAIL = """\
  <Wellbore>
    <eml:ContentType>application/x-witsml+xml;version=2.0;type=Wellbore</eml:ContentType>
    <eml:Title>58/1-A1 T2</eml:Title>
    <eml:Uuid>0b6f3f52-6a55-4c1b-a0a5-3b9a5f7c2d10</eml:Uuid>
  </Wellbore>
</Trajectory>
"""
FIRST_STATION_LINE = 17


def station(k: int, kind: str, tool: str | None, md: float, inc: float, azi: float) -> str:
    """One ``TrajectoryStation`` on one line, elements in schema order."""
    typed = f"<TypeTrajStation>{kind}</TypeTrajStation>"
    typed += f"<TypeSurveyTool>{tool}</TypeSurveyTool>" if tool else ""
    return (
        f'  <TrajectoryStation uid="s{k}"><ManuallyEntered>false</ManuallyEntered>{typed}'
        f'<Md uom="ft" datum="KB">{md}</Md><Incl uom="dega">{inc}</Incl>'
        f'<Azi uom="dega">{azi}</Azi></TrajectoryStation>\n'
    )


def document(
    tmp_path: Path, stations=STATIONS, *, version: str = "2.0", growing: str = "closed"
) -> Path:
    path = tmp_path / "trajectory.xml"
    body = "".join(station(k, *row) for k, row in enumerate(stations))
    path.write_text(HEAD.format(version=version, growing=growing) + body + TAIL)
    return path


def test_a_witsml_2_trajectory_is_read_in_its_units_north_and_tools(tmp_path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = gp.read(document(tmp_path), kind="stations")  # the reader found by content
    assert table["md"].tolist() == pytest.approx([r[2] * FT for r in STATIONS], abs=1e-9)
    assert table["inc"].tolist() == [r[3] for r in STATIONS]
    assert table["azi"].tolist() == [r[4] for r in STATIONS]
    assert table["station_type"].tolist() == ["tie in point", *["gyro north seeking"] * 3]
    assert table["source_line"].tolist() == [FIRST_STATION_LINE + k for k in range(4)]
    assert table.attrs["north_reference"] == "grid"
    well = table.attrs["well"]
    assert well["grid_convergence_applied"] == 1.25
    assert well["wellbore"] == "58/1-A1 T2"
    assert well["service_company"] == "Example Survey Co"
    assert well["survey_date"] == "2026-03-02"
    assert well["tool_type"] == "gyroscopic north seeking"
    assert well["latitude"] == 61.25  # gyropipe's extension value


@pytest.mark.parametrize(
    ("kind", "why"),
    [("MD and INCL", "an inclination-only survey"), ("interpolated", "interpolated between")],
)
def test_a_station_of_no_measured_direction_is_left_out_at_its_line(
    tmp_path: Path, kind: str, why: str
):
    rows = [*STATIONS[:2], (kind, None, 1050.0, 1.0, 0.0), *STATIONS[2:]]
    path = document(tmp_path, rows)
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == pytest.approx([r[2] * FT for r in STATIONS], abs=1e-9)
    (told,) = [str(w.message) for w in caught]
    assert told.startswith(f"{path}:{FIRST_STATION_LINE + 2}: station at md 320.04 m left out")
    assert f"typeTrajStation {kind!r} ({why}" in told


def test_a_growing_trajectory_is_warned_of(tmp_path: Path):
    with pytest.warns(InputFileWarning, match="objectGrowing true: the store was still adding"):
        gp.read(document(tmp_path, growing="active"), kind="stations")


@pytest.mark.parametrize("version", ["2.1", "1.4.1.1", ""])
def test_a_version_other_than_2_0_is_refused_at_the_root(tmp_path: Path, version: str):
    path = document(tmp_path, version=version)
    with pytest.raises(InputFileError) as caught:
        gp.read(path, kind="stations", reader="witsml")
    assert str(caught.value).startswith(f"{path}:2: schemaVersion {version!r}: this reader")


def test_the_survey_pipeline_integrates_a_witsml_2_trajectory(tmp_path: Path):
    """Through the CLI: the same trajectory as a CSV listing in grid north gives the same
    positions."""
    listing = tmp_path / "listing.csv"
    listing.write_text(
        "MD (ft),Inc (deg),Azi Grid (deg)\n"
        + "".join(f"{md},{inc},{azi}\n" for _, _, md, inc, azi in STATIONS)
    )
    pipeline = survey_pipeline(tmp_path)
    positions = []
    for name, stations in (("csv", listing), ("xml", document(tmp_path))):
        out = tmp_path / name
        args = ("run", pipeline, "--input", f"stations={stations}", "--out", out)
        gyropipe_cli(*args, "--well", "grid_convergence_applied=1.25", check=True)
        with (out / "trajectory.csv").open() as fh:
            rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
        positions.append([(r["md[m]"], r["tvd[m]"], r["north[m]"], r["east[m]"]) for r in rows])
    assert positions[0] == positions[1]
    assert float(positions[1][-1][2]) < 0 < float(positions[1][-1][3])  # south-east, 127.5°


def test_a_witsml_2_stations_matrix_cov_is_read_in_square_metres(tmp_path: Path):
    """2.0's ``MatrixCov`` (``VarianceNN`` … ``VarianceVertVert``, an AreaMeasure each) is
    1.4.1.1's ``matrixCov``: ft² from the store read as m² (1 ft² = 0.09290304 m²), and the
    frame states the covariances (1 σ², no error model named by the file)."""
    names = ("NN", "NE", "NVert", "EE", "EVert", "VertVert")
    body = ""
    for k, row in enumerate(STATIONS):
        values = (1.0 + k, 0.1, 0.01, 2.0 + k, 0.02, 0.5)
        cov = "".join(
            f'<Variance{n} uom="ft2">{v}</Variance{n}>' for n, v in zip(names, values, strict=True)
        )
        body += station(k, *row).replace(
            "</TrajectoryStation>", f"<MatrixCov>{cov}</MatrixCov></TrajectoryStation>"
        )
    path = tmp_path / "trajectory.xml"
    path.write_text(HEAD.format(version="2.0", growing="closed") + body + TAIL)
    table = gp.read(path, kind="stations")
    ft2 = 0.09290304
    assert table["cov_nn"].tolist() == pytest.approx([(1 + k) * ft2 for k in range(4)], rel=1e-12)
    assert table["cov_ee"].tolist() == pytest.approx([(2 + k) * ft2 for k in range(4)], rel=1e-12)
    assert table["cov_nv"].tolist() == pytest.approx([0.01 * ft2] * 4, rel=1e-12)
    assert table["cov_vv"].tolist() == pytest.approx([0.5 * ft2] * 4, rel=1e-12)
    (family,) = table.attrs["uncertainty"]["columns"]
    assert family["family"] == "covariance"
    assert family["scale"] == "1 sigma squared"
