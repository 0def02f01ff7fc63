"""WITSML 1.4.1.1 trajectory export and ingest: exports of a real run validated against the
WITSML write schema (komle's PyXB bindings of the Energistics XSDs, an independent parser),
every number round-tripped bit for bit through it and through our reader, the export read
back by a pipeline, several surveys, tool types, refusals, unit conversions, typed errors
with their lines, and a mutation fuzz test of the reader."""

from __future__ import annotations

import datetime as dt
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from export_support import SAMPLE, run_yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from komle.bindings.v1411.write import witsml as wml

import pipeline as gp
from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError, InputFileWarning
from pipeline.io import witsml as witsml_plugin
from pipeline.io.witsml.terms import survey_tool
from pipeline.runner import RunResult
from pipeline.tables import Stations
from pipeline.well import WellMetadata, well_of
from tests_support import mutate_bytes, pipeline_yaml, plugin_io, survey_stages

READER, WRITER = plugin_io(witsml_plugin)
NS = "http://www.witsml.org/schemas/1series"
STATION_ELEMENTS = {
    "md": "md",
    "tvd": "tvd",
    "inc": "incl",
    "azi": "azi",
    "north": "dispNs",
    "east": "dispEw",
    "vertical_section": "vertSect",
    "dls": "dls",
}
UOMS = {"md": "m", "tvd": "m", "inc": "dega", "azi": "dega", "north": "m", "east": "m"}
COVARIANCE = {
    "cov_nn": "varianceNN",
    "cov_ne": "varianceNE",
    "cov_nv": "varianceNVert",
    "cov_ee": "varianceEE",
    "cov_ev": "varianceEVert",
    "cov_vv": "varianceVertVert",
}


def schema_parse(path: Path) -> Any:
    """The document parsed and validated by the WITSML 1.4.1.1 write-schema bindings."""
    return wml.CreateFromDocument(path.read_bytes())


def column(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(), dtype=np.float64)


def test_export_is_valid_witsml_and_keeps_every_number(
    exports_run: RunResult, trajectory: pa.Table
):
    doc = schema_parse(exports_run.out_dir / "trajectory.xml")
    assert doc.version == "1.4.1.1"
    (traj,) = doc.trajectory
    assert (traj.uidWell, traj.uidWellbore) == ("05-123-45678", "J-12_ST1")
    assert (traj.nameWell, traj.nameWellbore, traj.serviceCompany) == (
        "J-12",
        "J-12 ST1",
        "Gyro Services",
    )
    assert traj.aziRef == "grid north"
    assert (traj.gridCorUsed.value(), traj.gridCorUsed.uom) == (1.25, "dega")
    assert (
        traj.magDeclUsed is None
    )  # the site's declination (17°) was never applied to gyro azimuths
    assert traj.aziVertSect.value() == 30.0
    assert traj.dispNsVertSectOrig.value() == traj.dispEwVertSectOrig.value() == 0.0
    assert traj.dTimTrajStart == dt.datetime(2026, 11, 21, tzinfo=dt.UTC)
    md = column(trajectory, "md")
    assert (traj.mdMn.value(), traj.mdMx.value()) == (md[0], md[-1])
    stations = traj.trajectoryStation
    assert len(stations) == trajectory.num_rows == 85
    assert [s.typeTrajStation for s in stations[:2]] == ["tie in point", "unknown"]
    assert {s.typeSurveyTool for s in stations} == {"unknown"}  # 'gyro (example)' names none
    assert {s.calcAlgorithm for s in stations} == {"minimum curvature"}
    for name, element in STATION_ELEMENTS.items():
        written = np.array([getattr(s, element).value() for s in stations])
        np.testing.assert_array_equal(written, column(trajectory, name), err_msg=name)
        uoms = {getattr(s, element).uom for s in stations}
        assert uoms == {UOMS.get(name, "dega/30m" if name == "dls" else "m")}
    for name, element in COVARIANCE.items():
        written = np.array([getattr(s.matrixCov, element).value() for s in stations])
        np.testing.assert_array_equal(written, column(trajectory, name), err_msg=name)
    assert column(trajectory, "cov_nn")[-1] > 1.0  # real uncertainty, not zeros
    extensions = {e.name: e.value_ for e in traj.commonData.extensionNameValue}
    assert float(extensions["gyropipe.well.latitude"].value()) == 61.25
    assert extensions["gyropipe.well.latitude"].uom == "dega"
    assert extensions["gyropipe.well.field"].value() == "Samotlor"


def test_reader_reads_the_export_back_exactly(exports_run: RunResult, trajectory: pa.Table):
    path = exports_run.out_dir / "trajectory.xml"
    assert READER.sniff(path)
    table, well = READER.read(path, "stations", READER.options())
    Stations.validate_table(table)
    for name in ("md", "inc", "azi", "tvd", "north", "east", "dls"):
        np.testing.assert_array_equal(column(table, name), column(trajectory, name), name)
        assert (
            table.schema.field(name).metadata[UNIT_KEY]
            == trajectory.schema.field(name).metadata[UNIT_KEY]
        )
    assert table.schema.field("azi").metadata[NORTH_KEY] == b"grid"
    assert table.column("source_line").to_pylist()[:2] == [16, 37]  # <trajectoryStation> lines
    assert well == well_of(trajectory)
    assert (well.declination, well.grid_convergence, well.wellbore) == (17.0, 1.25, "J-12 ST1")


def test_a_pipeline_ingests_the_export(
    exports_run: RunResult, trajectory: pa.Table, tmp_path: Path
):
    again = run_yaml(
        pipeline_yaml(survey_stages(vs_azimuth=30.0), name="ingest", well=None),
        {"stations": exports_run.out_dir / "trajectory.xml"},
        tmp_path / "out",
    )
    back = again.tables[("trajectory", "trajectory")]
    for name in ("md", "inc", "azi"):
        np.testing.assert_array_equal(column(back, name), column(trajectory, name))
    for name in ("tvd", "north", "east", "vertical_section", "dls"):
        np.testing.assert_allclose(column(back, name), column(trajectory, name), atol=1e-9)
    assert back.schema.field("azi").metadata[NORTH_KEY] == b"grid"
    assert again.well.grid_convergence == 1.25 and again.well.latitude == 61.25


def _stations(columns: dict[str, list[Any]], north: str | None = "true") -> pa.Table:
    return Stations.compiled().make_table(columns, north_reference=north)


def test_several_surveys_become_several_trajectories(tmp_path: Path):
    table = _stations(
        {
            "survey": ["run 1", "run 1", "run 2", "run 2", "run 2"],
            "md": [0.0, 100.0, 50.0, 75.5, 120.25],
            "inc": [0.0, 1.5, 2.0, 2.5, 3.0],
            "azi": [0.0, 45.0, 90.0, 91.0, 359.5],
        }
    )
    path = tmp_path / "two.xml"
    WRITER.write(table, path, WellMetadata(well="W-2", tool_type="gyro north-seeking"))
    doc = schema_parse(path)
    assert [t.name for t in doc.trajectory] == ["run 1", "run 2"]
    assert [len(t.trajectoryStation) for t in doc.trajectory] == [2, 3]
    first, later = doc.trajectory[1].trajectoryStation[:2]
    assert (first.typeTrajStation, later.typeTrajStation) == ("tie in point", "gyro north seeking")
    assert later.typeSurveyTool == "gyroscopic north seeking"
    assert later.calcAlgorithm is None and later.tvd is None  # stations: no method, no tvd
    back, well = READER.read(path, "stations", READER.options())
    assert back.column("survey").to_pylist() == table.column("survey").to_pylist()
    for name in ("md", "inc", "azi"):
        assert back.column(name).to_pylist() == table.column(name).to_pylist()
    assert back.column_names == [
        "survey",
        "md",
        "inc",
        "azi",
        "tool_type",
        "station_type",
        "source_line",
    ]
    assert back.column("tool_type").to_pylist()[:2] == ["gyroscopic north seeking"] * 2
    assert back.column("station_type").to_pylist()[:2] == ["tie in point", "gyro north seeking"]
    assert well == WellMetadata(well="W-2", tool_type="gyro north-seeking", north_reference="true")
    one, _ = READER.read(path, "stations", READER.options(trajectory="run 2"))
    assert one.column("md").to_pylist() == [50.0, 75.5, 120.25]


def test_a_well_without_a_name_is_written_as_unnamed(tmp_path: Path):
    path = tmp_path / "anon.xml"
    WRITER.write(
        _stations({"md": [0.0, 10.0], "inc": [0.0, 1.0], "azi": [0.0, 2.0]}), path, WellMetadata()
    )
    (traj,) = schema_parse(path).trajectory
    assert (traj.nameWell, traj.nameWellbore, traj.name, traj.uidWell) == (
        "unnamed",
        "unnamed",
        "survey",
        "unnamed",
    )


def _elementtree_text(path: Path) -> bytes:
    """The document at ``path`` parsed and written again by ElementTree (indented)."""
    root = ET.fromstring(path.read_bytes())
    for element in root.iter():  # the namespace as the plain attribute the writer sets
        element.tag = element.tag.removeprefix(f"{{{NS}}}")
    root.attrib = {"xmlns": NS, **root.attrib}
    ET.indent(root)
    text: bytes = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    return text + b"\n"


def test_the_document_is_what_elementtree_writes_of_it(exports_run: RunResult, tmp_path: Path):
    """The writer's text is ElementTree's serialisation of the same elements (escapes of
    text and attributes, empty elements, indentation), for a real run's export and for a
    well whose header holds characters XML escapes."""
    export = exports_run.out_dir / "trajectory.xml"
    assert export.read_bytes() == _elementtree_text(export)
    hostile = WellMetadata(
        well='A&B <"W-1">',
        wellbore="W-1 'ST'",
        company="R&D > ops",
        service_company="Gyro & <Co>",
        survey_date=dt.date(2024, 5, 1),
        latitude=-33.5,
    )
    table = _stations(
        {
            "survey": ["a&b", "a&b", 'c"d'],
            "md": [0.0, 100.0, 250.125],
            "inc": [0.0, 1.5, 2.0],
            "azi": [0.0, 45.0, 359.999],
        }
    )
    path = tmp_path / "hostile.xml"
    WRITER.write(table, path, hostile)
    assert path.read_bytes() == _elementtree_text(path)
    assert [t.name for t in schema_parse(path).trajectory] == ["a&b", 'c"d']


def test_a_station_lacks_only_the_numbers_it_lacks(trajectory: pa.Table, tmp_path: Path):
    """A station with a value not finite lacks that element alone; one with a covariance
    entry not finite lacks its matrixCov, the others keep theirs; the text is still
    ElementTree's serialisation of the elements."""

    def with_nan(table: pa.Table, name: str, row: int) -> pa.Table:
        values = column(table, name).copy()
        values[row] = np.nan
        index = table.schema.get_field_index(name)
        return table.set_column(index, table.schema.field(name), pa.array(values))

    table = with_nan(with_nan(trajectory, "dls", 5), "cov_ev", 3)
    path = tmp_path / "gaps.xml"
    WRITER.write(table, path, well_of(trajectory) or WellMetadata())
    assert path.read_bytes() == _elementtree_text(path)
    stations = schema_parse(path).trajectory[0].trajectoryStation
    assert [i for i, s in enumerate(stations) if s.matrixCov is None] == [3]
    assert [i for i, s in enumerate(stations) if s.dls is None] == [5]
    assert stations[4].matrixCov.varianceEVert.value() == column(trajectory, "cov_ev")[4]
    assert stations[3].dls.value() == column(trajectory, "dls")[3]


@pytest.mark.parametrize(
    ("tool_type", "expected"),
    [
        ("Gyro north-seeking (GWD70)", "gyroscopic north seeking"),
        ("north seeking gyro", "gyroscopic north seeking"),
        ("gyrocompass", "gyroscopic north seeking"),
        ("inertial gyro", "gyroscopic inertial"),
        ("Gyro-MWD", "gyroscopic MWD"),
        ("MWD", "magnetic MWD"),
        ("magnetic single shot", "magnetic single-shot"),
        ("EMS multishot", "magnetic multiple-shot"),
        ("gyroscopic north seeking", "gyroscopic north seeking"),
        ("gyro (example)", "unknown"),
        ("simulated mems-vrg", "unknown"),
        (None, "unknown"),
    ],
)
def test_survey_tool_types(tool_type: str | None, expected: str):
    assert survey_tool(tool_type) == expected


@pytest.mark.parametrize(
    ("table", "well", "message"),
    [
        (
            _stations({"survey": [" "], "md": [0.0], "inc": [0.0], "azi": [0.0]}),
            WellMetadata(well="W", wellbore="  "),
            "wellbore name",
        ),
        (
            _stations({"md": [0.0], "inc": [0.0], "azi": [0.0]}),
            WellMetadata(well="x" * 65),
            "longer than the 64 characters",
        ),
        (
            _stations({"md": [0.0], "inc": [0.0], "azi": [0.0]}, north=None),
            WellMetadata(well="W"),
            "no north reference",
        ),
        (pa.table({"md": [0.0], "inc": [0.0]}), WellMetadata(well="W"), "need columns ['azi']"),
        (
            pa.table(
                {
                    "md": pa.array([0.0]),
                    "inc": pa.array([0.0]),
                    "azi": pa.array([0.0]),
                }
            ).cast(
                pa.schema(
                    [
                        pa.field("md", pa.float64(), metadata={UNIT_KEY: b"ft"}),
                        pa.field("inc", pa.float64(), metadata={UNIT_KEY: b"deg"}),
                        pa.field(
                            "azi", pa.float64(), metadata={UNIT_KEY: b"deg", NORTH_KEY: b"true"}
                        ),
                    ]
                )
            ),
            WellMetadata(well="W"),
            "column 'md' is in 'ft'",
        ),
        (
            _stations({"md": [0.0], "inc": [0.0], "azi": [0.0]}),
            WellMetadata(well="bell\x07"),
            "which XML cannot",
        ),
    ],
)
def test_writer_refuses_what_witsml_cannot_hold(
    tmp_path: Path, table: pa.Table, well: WellMetadata, message: str
):
    path = tmp_path / "x.xml"
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("(", r"\(")):
        WRITER.write(table, path, well)


STATION = (
    '    <trajectoryStation uid="s{i}"><typeTrajStation>unknown</typeTrajStation>'
    '<md uom="{md_uom}">{md}</md><incl uom="dega">{inc}</incl><azi uom="dega">{azi}</azi>'
    "</trajectoryStation>"
)


def document(
    stations: list[str] | None = None,
    head: str = "<aziRef>true north</aziRef>",
    root: str = f'trajectorys xmlns="{NS}" version="1.4.1.1"',
) -> str:
    """A small trajectory document: line 7 is ``head``, stations from line 8, one per line."""
    if stations is None:
        stations = [
            STATION.format(i=i, md_uom="m", md=md, inc=inc, azi=azi)
            for i, (md, inc, azi) in enumerate([(0, 0, 0), (100, 1.5, 45), (200, 3, 46.5)])
        ]
    body = "\n".join(stations)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f"<{root}>\n"
        '  <trajectory uidWell="w" uidWellbore="b" uid="t">\n'
        "    <nameWell>W-1</nameWell>\n"
        "    <nameWellbore>W-1</nameWellbore>\n"
        "    <name>t</name>\n"
        f"    {head}\n"
        f"{body}\n"
        "  </trajectory>\n"
        f"</{root.split()[0]}>\n"
    )


def put(tmp_path: Path, text: str, name: str = "t.xml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reader_converts_units(tmp_path: Path):
    stations = [
        '    <trajectoryStation uid="a"><md uom="ft">0</md><tvd uom="ftUS">0</tvd>'
        '<incl uom="rad">0</incl><azi uom="dega">0</azi><dls uom="dega/100ft">0</dls>'
        "</trajectoryStation>",
        '    <trajectoryStation uid="b"><md uom="ft">100</md><tvd uom="ftUS">100</tvd>'
        '<incl uom="rad">0.5</incl><azi uom="rad">1</azi><dls uom="dega/100ft">3</dls>'
        "</trajectoryStation>",
    ]
    head = (
        '<dTimTrajStart>2024-05-01T10:30:00+03:00</dTimTrajStart><magDeclUsed uom="rad">0.1'
        "</magDeclUsed><aziRef>true north</aziRef>"
    )
    table, well = READER.read(put(tmp_path, document(stations, head)), "stations", READER.options())
    assert table.column("md").to_pylist() == [0.0, 100 * 0.3048]
    assert table.column("tvd").to_pylist() == [0.0, pytest.approx(100 * 1200 / 3937, abs=1e-12)]
    assert table.column("inc").to_pylist() == [0.0, pytest.approx(np.degrees(0.5), abs=1e-12)]
    assert table.column("azi").to_pylist()[1] == pytest.approx(np.degrees(1.0), abs=1e-12)
    assert table.column("dls").to_pylist()[1] == pytest.approx(3 * 30 / 30.48, abs=1e-12)
    assert table.schema.field("azi").metadata[NORTH_KEY] == b"true"
    assert well.declination_applied == pytest.approx(np.degrees(0.1), abs=1e-12)
    assert well.declination is None  # what was applied, not the site's declination
    assert well.survey_date is not None and well.survey_date.isoformat() == "2024-05-01"
    assert (well.well, well.wellbore, well.north_reference) == ("W-1", None, "true")


def test_unknown_azimuth_reference_takes_the_option(tmp_path: Path):
    path = put(tmp_path, document(head="<aziRef>unknown</aziRef>"))
    table, _ = READER.read(path, "stations", READER.options(default_north_reference="grid"))
    assert table.schema.field("azi").metadata[NORTH_KEY] == b"grid"


def _bad_station(**replace: str) -> list[str]:
    fields = {"i": "0", "md_uom": "m", "md": "0", "inc": "0", "azi": "0"} | replace
    return [STATION.format(**fields)]


@pytest.mark.parametrize(
    ("text", "options", "message", "line"),
    [
        (document().replace("</md>", "</mdx>", 1), {}, "not well-formed XML: mismatched tag", 8),
        (document().replace("</trajectorys>", ""), {}, "no element found", 13),  # at EOF
        (document(root=f'log xmlns="{NS}" version="1.4.1.1"'), {}, "root element is <log>", 2),
        (
            document(
                root='trajectorys xmlns="http://www.witsml.org/schemas/131" version="1.3.1.1"'
            ),
            {},
            "in namespace 'http://www.witsml.org/schemas/131'",
            2,
        ),
        (document(root=f'trajectorys xmlns="{NS}" version="1.3.1.1"'), {}, "version '1.3.1.1'", 2),
        (document(_bad_station(inc="abc")), {}, "<incl> 'abc' is not a number", 8),
        (document(_bad_station(azi="4_5")), {}, "<azi> '4_5' is not a number", 8),  # not 45
        (document(_bad_station(azi="-1e999")), {}, "<azi> '-1e999' is not a finite number", 8),
        (document(_bad_station(md="inf")), {}, "<md> 'inf' is not a finite number", 8),
        (
            document(_bad_station(md="100", inc="-999.2500")),  # the null, to 4 decimals
            {},
            "<incl> -999.2500 is a null marker: expected an angle",
            8,
        ),
        (
            document(_bad_station(md="-999.25")),
            {},
            "<md> -999.25 is a null marker: expected a length",
            8,
        ),
        (document(_bad_station(md_uom="furlong")), {}, "uom 'furlong' is not supported", 8),
        (
            document([STATION.replace(' uom="{md_uom}"', "").format(i=0, md=0, inc=0, azi=0)]),
            {},
            "<md> has no uom",
            8,
        ),
        (
            document(
                [STATION.replace('<md uom="{md_uom}">{md}</md>', "").format(i=0, inc=0, azi=0)]
            ),
            {},
            "trajectoryStation has no <md>",
            8,
        ),
        (
            document().replace(
                "<trajectorys", '<!DOCTYPE trajectorys [<!ENTITY x "y">]>\n<trajectorys'
            ),
            {},
            "DOCTYPE and entity declarations are not accepted",
            2,
        ),
        (document(head="<aziRef>unknown</aziRef>"), {}, "aziRef is absent or 'unknown'", 3),
        (document(head="<aziRef>north-ish</aziRef>"), {}, "aziRef 'north-ish'", 7),
        (
            document(head="<aziRef>grid north</aziRef>"),
            {"north_reference": "true"},
            "contradicts the option north_reference",
            7,
        ),
        (document([]), {}, "trajectory has no trajectoryStation", 3),
        (
            f'<?xml version="1.0"?>\n<trajectorys xmlns="{NS}" version="1.4.1.1"/>\n',
            {},
            "no <trajectory> element",
            2,
        ),
        (
            document(head="<dTimTrajStart>yesterday</dTimTrajStart><aziRef>true north</aziRef>"),
            {},
            "not an ISO 8601",
            7,
        ),
        (
            document(
                head="<aziRef>true north</aziRef><commonData><extensionNameValue uid='x'>"
                "<name>gyropipe.well.latitude</name><value uom='dega'>95</value>"
                "<dataType>double</dataType></extensionNameValue></commonData>"
            ),
            {},
            "latitude 95.0: Input should be less than or equal to 90",
            7,
        ),
        (document(), {"trajectory": "nope"}, "no trajectory with uid or name 'nope'", 0),
    ],
)
def test_malformed_input_is_a_typed_error_with_its_line(
    tmp_path: Path, text: str, options: dict[str, Any], message: str, line: int
):
    path = put(tmp_path, text)
    with pytest.raises(InputFileError) as caught:
        READER.read(path, "stations", READER.options(**options))
    assert message in str(caught.value)
    assert caught.value.path == str(path)
    assert caught.value.line == line


def test_sniff_recognises_witsml_only(tmp_path: Path):
    assert READER.sniff(put(tmp_path, document()))
    assert not READER.sniff(SAMPLE)
    assert not READER.sniff(put(tmp_path, "<trajectorys/>", "other.xml"))
    assert not READER.sniff(tmp_path / "missing.xml")


@pytest.mark.parametrize("encoding", ["UTF--180", "utf-32", "base64", "idna"])
def test_an_unusable_declared_encoding_is_located(tmp_path: Path, encoding: str):
    """Fuzz finding (a number replaced in the XML declaration): expat's LookupError or
    ValueError on the encoding escaped the reader as a traceback."""
    text = document()
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>')
    path = put(tmp_path, text.replace('encoding="UTF-8"', f'encoding="{encoding}"', 1))
    with pytest.raises(InputFileError, match="unusable encoding in the XML declaration") as caught:
        READER.read(path, "stations", READER.options(default_north_reference="true"))
    assert caught.value.path == str(path) and caught.value.line == 1


VALID = document().encode()


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["flip", "truncate", "insert", "delete", "delete_line"]),
            st.integers(0, len(VALID)),
            st.integers(0, 255),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_mutated_files_raise_typed_errors_or_read_what_expat_reads(
    tmp_path: Path, mutations: list[tuple[str, int, int]]
):
    path = tmp_path / "fuzz.xml"
    data = mutate_bytes(VALID, mutations)
    path.write_bytes(data)
    error: InputFileError | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            table, _ = READER.read(path, "stations", READER.options(default_north_reference="true"))
        except InputFileError as exc:
            error = exc
    if error is not None:
        assert error.path == str(path)
        return
    root = ET.fromstring(data)  # an independent parser accepts what we read
    # a station whose type the mutation made none of WITSML's ('unknwn') is left out, told
    left_out = sum(
        bool(re.search(r": station (at md \S+ m )?left out: ", str(w.message))) for w in caught
    )
    stations = len(root.findall(f".//{{{NS}}}trajectoryStation"))
    assert table.num_rows + left_out == stations and table.num_rows >= 1


def test_tvd_from_another_datum_than_md_is_left_out_with_a_warning(tmp_path: Path):
    # an operator's store: MDs from the KB (25 m above MSL), TVDs below sea level (TVDSS)
    stations = [
        f'    <trajectoryStation uid="s{md}"><md uom="m" datum="KB">{md}</md>'
        f'<tvd uom="m" datum="{datum}">{tvd}</tvd><incl uom="dega">0</incl>'
        '<azi uom="dega">0</azi></trajectoryStation>'
        for md, tvd, datum in ((0, -25, "MSL"), (100, 75, "MSL"), (200, 200, "KB"))
    ]
    path = put(tmp_path, document(stations, "<aziRef>true north</aziRef>"))
    with pytest.warns(InputFileWarning, match=r"t\.xml:\d+: <tvd> of 2 station\(s\) left out"):
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 100.0, 200.0]
    assert table["tvd"].isna().tolist() == [True, True, False]
    assert table["tvd"].iloc[2] == 200.0  # the station whose datums agree keeps its TVD


def _stations_on(datums: tuple[str, ...]) -> list[str]:
    """Stations at md 0, 100, 200 m, each ``md`` naming a datum ('' none) as stores write it."""
    return [
        f'    <trajectoryStation uid="s{k}"><md uom="m"{f" datum={d!r}" if d else ""}>{100 * k}'
        f'</md><incl uom="dega">{1.5 * k}</incl><azi uom="dega">45</azi></trajectoryStation>'
        for k, d in enumerate(datums)
    ]


def test_md_from_two_datums_is_refused_at_the_line(tmp_path: Path):
    path = put(tmp_path, document(_stations_on(("KB", "", "DF"))))  # wellDatum uids
    with pytest.raises(
        InputFileError, match="datum 'DF' differs from the 'KB' at line 8"
    ) as caught:
        gp.read(path, kind="stations")
    assert (caught.value.line, caught.value.column) == (10, "md")
    same = put(tmp_path, document(_stations_on(("KB", "", "KB"))))  # none named: the default
    assert gp.read(same, kind="stations").shape[0] == 3


RANGE = '<mdMn uom="{uom}"{datum}>{low}</mdMn><mdMx uom="{uom}"{datum}>{high}</mdMx>'


def _ranged(tmp_path: Path, low: float, high: float, uom: str = "m", datum: str = "") -> Path:
    """Stations at md 0 to 200 m under a trajectory stating mdMn/mdMx (line 7)."""
    head = RANGE.format(uom=uom, datum=datum, low=low, high=high) + "<aziRef>true north</aziRef>"
    return put(tmp_path, document(head=head))


def test_a_range_reaching_past_the_stations_warns_of_missing_stations(tmp_path: Path):
    # a store's export cut short: mdMx says the trajectory goes on to 3000 m
    with pytest.warns(InputFileWarning, match=r"t\.xml:7: mdMx 3000\.0 m reaches past the last"):
        assert gp.read(_ranged(tmp_path, 0, 3000), kind="stations")["md"].max() == 200.0
    with pytest.warns(InputFileWarning, match=r"t\.xml:7: mdMn -50\.0 m reaches past the first"):
        gp.read(_ranged(tmp_path, -50, 200), kind="stations")


def test_a_station_outside_the_range_warns_at_its_line(tmp_path: Path):
    with pytest.warns(InputFileWarning, match=r"t\.xml:8: station md 0\.0 m lies outside .* mdMn"):
        gp.read(_ranged(tmp_path, 50, 200), kind="stations")
    with pytest.warns(InputFileWarning, match=r"t\.xml:10: station md 200\.0 m .* mdMx 150\.0"):
        gp.read(_ranged(tmp_path, 0, 150), kind="stations")


def test_an_unreadable_range_is_warned_of_and_the_stations_read(tmp_path: Path):
    head = '<mdMn uom="m"></mdMn><mdMx>300</mdMx><aziRef>true north</aziRef>'
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(put(tmp_path, document(head=head)), kind="stations")
    assert table["md"].tolist() == [0.0, 100.0, 200.0]
    told = sorted(str(w.message).split(": ", 1)[1] for w in caught)
    assert told == [
        "<mdMn> '' is not a number; the stations are not checked against it",
        "<mdMx> has no uom; the stations are not checked against it",
    ]


def test_a_range_in_its_own_unit_or_on_another_datum_does_not_warn(tmp_path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        gp.read(_ranged(tmp_path, 0, 656.168, uom="ft"), kind="stations")  # 200.0000064 m
        gp.read(_ranged(tmp_path, 0, 3000, datum=' datum="MSL"'), kind="stations")  # not KB's


DEPTH_REFERENCE = (
    "<commonData><extensionNameValue><name>gyropipe.well.depth_reference</name>"
    "<value>{}</value></extensionNameValue></commonData><aziRef>true north</aziRef>"
)


def test_md_on_another_datum_than_the_depth_reference_is_refused(tmp_path: Path):
    stations = _stations_on(("DF", "DF", "DF"))
    path = put(tmp_path, document(stations, DEPTH_REFERENCE.format("RKB")))
    with pytest.raises(InputFileError, match="datum 'DF' is not the depth reference 'RKB'") as e:
        gp.read(path, kind="stations")
    assert (e.value.line, e.value.column) == (8, "md")
    path = put(tmp_path, document(_stations_on(("KB",) * 3), DEPTH_REFERENCE.format("RKB")))
    assert gp.read(path, kind="stations").attrs["well"]["depth_reference"] == "RKB"
    path = put(tmp_path, document(_stations_on(("wd-1",) * 3), DEPTH_REFERENCE.format("RKB")))
    assert gp.read(path, kind="stations").shape[0] == 3  # a uid naming no datum: unknown
