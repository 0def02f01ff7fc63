"""Vendor profiles of the CSV reader: the bundled examples on files in their vendors'
formats, merging under explicit options, located errors in bad profiles, and fuzzing of
profile-driven reads (mutated data and mutated profiles)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from pipeline.errors import InputFileError, ReaderOptionsError, SpecError, UnitError
from pipeline.io import csv as csv_plugin
from pipeline.io.conventions import to_canonical
from pipeline.io.csv.options import CsvOptions, load_profile
from pipeline.io.mnemonics import CURVES
from pipeline.registry import Registry
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.tables import RawSamples, Stations
from pipeline.units import conversion_factor
from pipeline.well import WellMetadata
from tests_support import line_ops, mutate_lines, plugin_io

ROOT = Path(__file__).resolve().parents[2]
PROFILES = ROOT / "examples" / "profiles"
ACME_GYRO = PROFILES / "acme-gyro-csv.yaml"
ACME_REPORT = PROFILES / "wellpath-report.yaml"
G = 9.80665


READER = plugin_io(csv_plugin)[0]


def put(tmp_path: Path, content: str | bytes, name: str) -> Path:
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def read(path: Path, kind: str, **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, kind, READER.options.model_validate(options))


def column(table: pa.Table, name: str) -> list[Any]:
    return list(table.column(name).to_pylist())


GYRO_LOG = (
    "ACME GYROLOG v2 CSV EXPORT\n"
    "WELL=Demo-1\n"
    "SERIAL=AG-1093\n"
    "LAT=61.25\n"
    "LON=73.4\n"
    "DATE=2026-11-21\n"
    "T,DEPTH,FANG,WX,WY,WZ,AX,AY,AZ,STN,POS\n"
    "0,5000,0,0.001,-0.002,0.003,0.01,-0.02,0.98,0,\n"
    "0.01,5000.5,1.5707963267948966,0.004,0.005,0.006,0.03,0.04,0.99,,1\n"
)
REPORT = (
    "WELLPATH REPORT\n"
    "Well: A-12\n"
    "\n"
    "Measured Depth [ft],Incl. [deg],Azim. [deg],TVD [m],Local N [m],Local E [m],"
    "DLS [deg/100ft]\n"
    "0,0,0,0,0,0,0\n"
    "1000,10,45,302.9,18.7,18.7,1\n"
    "End of report\n"
)


def test_example_gyro_profile(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, GYRO_LOG, "log.csv"), "samples", profile=ACME_GYRO)
    assert well == WellMetadata(
        well="Demo-1",
        tool_serial="AG-1093",
        latitude=61.25,
        longitude=73.4,
        survey_date="2026-11-21",
    )
    assert column(table, "time") == [0.0, 0.01]
    assert column(table, "md") == [5000 * 0.3048, 5000.5 * 0.3048]
    # axes [y, x, -z], rates in deg/s, accelerometers in g reading −g (specific force)
    assert column(table, "gyro_x") == pytest.approx([-0.002 * 3600, 0.005 * 3600])
    assert column(table, "gyro_y") == pytest.approx([0.001 * 3600, 0.004 * 3600])
    assert column(table, "gyro_z") == pytest.approx([-0.003 * 3600, -0.006 * 3600])
    assert column(table, "acc_x") == pytest.approx([0.02 * G, -0.04 * G])
    assert column(table, "acc_y") == pytest.approx([-0.01 * G, -0.03 * G])
    assert column(table, "acc_z") == pytest.approx([0.98 * G, 0.99 * G])
    assert column(table, "frame_angle") == [0.0, 270.0]  # rad, counterclockwise
    assert column(table, "station") == [0, None]
    assert column(table, "position") == [None, 1]
    assert column(table, "source_line") == [8, 9]
    RawSamples.validate_table(table)


def test_gyro_profile_reads_vendor_data_back_to_the_simulation(tmp_path: Path) -> None:
    """Simulator samples turned into an Acme CSV export (Acme units and axes) read back."""
    samples = simulate(
        SimulationSpec.model_validate(
            {
                "name": "acme",
                "seed": 1,
                "site": {
                    "latitude": 61.25,
                    "longitude": 73.4,
                    "elevation": 120.0,
                    "date": "2026-11-21",
                    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
                },
                "well": {"sections": [{"kind": "curve", "dls": 30.0, "inc": 20, "azi": 40}]},
                "tool": {"preset": "ideal"},
                "survey": {
                    "mode": "point",
                    "every": 10,
                    "dwell": 1.0,
                    "move_time": 0.5,
                    "speed": 5,
                },
            }
        )
    ).samples
    profile = load_profile(ACME_GYRO)
    vendor = to_canonical(samples, profile.conventions)  # Acme's conventions are involutions
    channels = {
        "T": "time",
        "DEPTH": "md",
        "FANG": "frame_angle",
        "WX": "gyro_x",
        "WY": "gyro_y",
        "WZ": "gyro_z",
        "AX": "acc_x",
        "AY": "acc_y",
        "AZ": "acc_z",
        "MX": "mag_x",
        "MY": "mag_y",
        "MZ": "mag_z",
        "STN": "station",
        "POS": "position",
    }
    columns = []
    for name in channels.values():
        values = vendor.column(name)
        if name in profile.units:
            values = pc.divide(
                values, conversion_factor(profile.units[name], CURVES[name].quantity or "")
            )
        columns.append(values)
    path = tmp_path / "export.csv"
    with path.open("wb") as fh:
        fh.write(b"ACME GYROLOG v2 CSV EXPORT\nWELL=Demo-1\nSERIAL=AG-1093\nLAT=61.25\n")
        fh.write(b"LON=73.4\nDATE=2026-11-21\n" + ",".join(channels).encode() + b"\n")
        pacsv.write_csv(
            pa.table(columns, names=list(channels)), fh, pacsv.WriteOptions(include_header=False)
        )
    table, _ = read(path, "samples", profile=ACME_GYRO)
    for name in channels.values():
        expected = samples.column(name).to_numpy(zero_copy_only=False)
        got = table.column(name).to_numpy(zero_copy_only=False)
        if name in ("station", "position"):
            assert table.column(name).equals(samples.column(name))
        elif name == "frame_angle":  # 360° ≡ 0°
            np.testing.assert_allclose(np.cos(np.radians(got - expected)), 1.0, atol=1e-12)
        else:
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-9, err_msg=name)
    RawSamples.validate_table(table)


def test_example_report_profile(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, REPORT, "report.csv"), "stations", profile=ACME_REPORT)
    assert well.well == "A-12"
    assert table.column_names == [
        *("md", "inc", "azi", "tvd", "north", "east", "dls"),
        "source_line",
    ]
    assert column(table, "md") == [0.0, 304.8]
    assert column(table, "tvd") == [0.0, 302.9]
    assert column(table, "north") == [0.0, 18.7]
    assert column(table, "dls") == pytest.approx([0.0, 30 / 30.48])
    assert table.schema.field("azi").metadata[b"north_reference"] == b"grid"
    assert table.schema.field("dls").metadata[b"unit"] == b"deg/30m"
    Stations.validate_table(table)


def test_profile_path_is_relative_to_the_current_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    path = put(tmp_path, REPORT, "report.csv")
    table, _ = read(path, "stations", profile="examples/profiles/wellpath-report.yaml")
    assert column(table, "md") == [0.0, 304.8]


def test_a_header_unit_the_profile_contradicts_is_refused(tmp_path: Path) -> None:
    """Acme's later exports state DEPTH [m]: the profile's md: ft (for headers without a
    unit) read them 3.28 times too deep."""
    path = put(tmp_path, GYRO_LOG.replace(",DEPTH,", ",DEPTH [m],"), "log.csv")
    with pytest.raises(
        InputFileError, match=r"header says 'm', the profile's unit .* 'ft'"
    ) as info:
        read(path, "samples", profile=ACME_GYRO)
    assert (info.value.line, info.value.column) == (7, "DEPTH [m]")
    table, _ = read(path, "samples", profile=ACME_GYRO, md_unit="m")  # explicit: the user's
    assert column(table, "md") == [5000.0, 5000.5]
    feet = put(tmp_path, GYRO_LOG.replace(",DEPTH,", ",DEPTH (feet),"), "feet.csv")
    table, _ = read(feet, "samples", profile=ACME_GYRO)  # the same unit, spelled otherwise
    assert column(table, "md") == [5000 * 0.3048, 5000.5 * 0.3048]
    noted = put(tmp_path, GYRO_LOG.replace(",DEPTH,", ",DEPTH (MD),"), "noted.csv")
    table, _ = read(noted, "samples", profile=ACME_GYRO)  # no unit in the brackets
    assert column(table, "md") == [5000 * 0.3048, 5000.5 * 0.3048]


def test_explicit_options_win_over_the_profile(tmp_path: Path) -> None:
    text = GYRO_LOG.replace(",DEPTH,", ",TIEFE,")
    options = {
        "profile": ACME_GYRO,
        "md_unit": "m",  # replaces the profile's units.md
        "units": {"time": "min"},  # merged key by key with the profile's units
        "aliases": {"Tiefe": "md"},
        "conventions": {"accelerometer": "gravity"},  # the profile's axes stay
    }
    table, _ = read(put(tmp_path, text, "log.csv"), "samples", **options)
    assert column(table, "md") == [5000.0, 5000.5]
    assert column(table, "time") == [0.0, 0.6]
    assert column(table, "gyro_x") == pytest.approx([-0.002 * 3600, 0.005 * 3600])
    assert column(table, "acc_z") == pytest.approx([-0.98 * G, -0.99 * G])


def test_explicit_header_line_and_north_reference(tmp_path: Path) -> None:
    text = "Title\n" + REPORT.replace("WELLPATH REPORT\n", "")
    with pytest.raises(InputFileError, match="on line 1 \\(option header_line\\)"):
        read(put(tmp_path, text, "r.csv"), "stations", profile=ACME_REPORT, header_line=1)
    table, _ = read(put(tmp_path, text, "r.csv"), "stations", profile=ACME_REPORT, header_line=4)
    assert column(table, "md") == [0.0, 304.8]
    with pytest.raises(InputFileError, match="conflicting north references"):
        read(
            put(tmp_path, text.replace("Azim.", "Azim. True"), "r.csv"),
            "stations",
            profile=ACME_REPORT,
        )
    table, _ = read(
        put(tmp_path, text.replace("Azim.", "Azim. True"), "r.csv"),
        "stations",
        profile=ACME_REPORT,
        north_reference="true",
    )
    assert table.schema.field("azi").metadata[b"north_reference"] == b"true"


def test_profile_conflicting_with_the_options(tmp_path: Path) -> None:
    profile = put(tmp_path, "decimal: ','\n", "p.yaml")
    with pytest.raises(InputFileError) as info:
        read(put(tmp_path, REPORT, "r.csv"), "stations", profile=profile, delimiter=",")
    assert info.value.path == str(profile)
    assert "conflict with this profile" in str(info.value)
    assert "decimal ','" in str(info.value)


@pytest.mark.parametrize(
    ("text", "line", "located"),
    [
        ("delimiter: ';'\ndelimeter: ','\n", 2, "2:1: unknown field 'delimeter'"),
        ("decimal: x\n", 1, "1:10: decimal: Input should be '.' or ','"),
        ("header_line: 0\n", 1, "1:14: header_line: Input should be greater than or equal to 1"),
        ("aliases:\n  Zeit: tyme\n", 2, "2:9: aliases.Zeit: Value error, unknown column 'tyme'"),
        ("columns:\n  tyme: Zeit\n", 2, "unknown column 'tyme'"),
        ("units:\n  time: s\n  md: furlong\n", 2, "2:3: units: Value error, md: unknown unit"),
        ("conventions:\n  axes: [x, x, z]\n", 2, "2:9: conventions.axes: Value error, axes must"),
        ("north_reference: north\n", 1, "north_reference: Input should be 'true'"),
        ("delimiter: ';'\ndelimiter: ','\n", 2, "2:1: duplicate key 'delimiter'"),
        ("delimiter: [\n", 2, "malformed YAML"),
        ("- delimiter\n", 1, "1:1: a CSV profile must be a mapping of reader options"),
        ("", 1, "1:1: empty file"),
    ],
)
def test_invalid_profiles_are_located(tmp_path: Path, text: str, line: int, located: str) -> None:
    profile = put(tmp_path, text, "vendor.yaml")
    with pytest.raises(InputFileError) as info:
        read(put(tmp_path, REPORT, "r.csv"), "stations", profile=profile)
    err = info.value
    assert (err.path, err.line) == (str(profile), line)
    assert str(err).startswith(f"{profile}:{line}: invalid CSV profile")
    assert located in str(err)
    assert isinstance(err.__cause__, SpecError)


def test_every_problem_of_a_profile_is_listed(tmp_path: Path) -> None:
    profile = put(tmp_path, "decimal: x\nfoo: 1\nheader_line: -1\n", "vendor.yaml")
    with pytest.raises(InputFileError, match=r"\(3 problems\)") as info:
        CsvOptions(profile=profile).resolved()
    assert info.value.line == 1
    for where in ("vendor.yaml:1:10:", "vendor.yaml:2:1:", "vendor.yaml:3:14:"):
        assert where in str(info.value)


def test_unreadable_profiles(tmp_path: Path) -> None:
    with pytest.raises(ValidationError, match=r"no such file: .*absent\.yaml") as refused:
        CsvOptions(profile=tmp_path / "absent.yaml")  # refused with the options
    assert refused.value.errors()[0]["loc"] == ("profile",)
    with pytest.raises(ValidationError, match="not a regular file"):
        CsvOptions(profile=tmp_path)
    with pytest.raises(InputFileError, match="cannot read the profile"):
        load_profile(tmp_path / "absent.yaml")  # gone after the options were validated
    with pytest.raises(InputFileError, match="not UTF-8"):
        CsvOptions(profile=put(tmp_path, b"delimiter: '\xff'\n", "bad.yaml")).resolved()


# ----------------------------------------------------------------------------- fuzz

_op = line_ops()


def _typed_errors_only(path: Path, kind: str, profile: Path) -> None:
    try:
        table, _ = read(path, kind, profile=profile)
    except (InputFileError, UnitError):
        return
    assert table.num_rows >= 1
    assert "source_line" in table.column_names


@settings(max_examples=150, deadline=None, derandomize=True)
@given(ops=st.lists(_op, min_size=1, max_size=3))
def test_fuzz_data_read_with_a_profile(fuzz_dir: Path, ops: list[tuple[str, int, int]]) -> None:
    path = put(fuzz_dir, mutate_lines(GYRO_LOG.encode(), ops, b","), "log.csv")
    _typed_errors_only(path, "samples", ACME_GYRO)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(ops=st.lists(_op, min_size=1, max_size=3), kind=st.sampled_from(["samples", "stations"]))
def test_fuzz_mutated_profiles(fuzz_dir: Path, ops: list[tuple[str, int, int]], kind: str) -> None:
    source = ACME_GYRO if kind == "samples" else ACME_REPORT
    profile = put(fuzz_dir, mutate_lines(source.read_bytes(), ops, b":"), "profile.yaml")
    data = put(fuzz_dir, GYRO_LOG if kind == "samples" else REPORT, "data.csv")
    _typed_errors_only(data, kind, profile)


def test_unquoted_yaml_true_is_true_north(tmp_path: Path) -> None:
    profile = tmp_path / "p.yaml"
    profile.write_text("north_reference: true\n")
    assert CsvOptions.model_validate({"profile": str(profile)}).resolved().north_reference == "true"


def test_options_are_validated_once_by_the_model_the_reader_declares(tmp_path: Path):
    """Validating a pipeline and reading a file use the reader's own options model (one
    function), and the reader gets its instance; a well default fills an option not given."""
    registry = Registry()
    registry.readers["csv"] = (READER, "csv")
    parsed = READER.parse_options({"delimiter": ";"}, WellMetadata(north_reference="grid"))
    assert isinstance(parsed, CsvOptions)
    assert (parsed.delimiter, parsed.default_north_reference) == (";", "grid")
    with pytest.raises(ValidationError) as planned:
        registry.check_reader_options("stations", "csv", {"delimiter": ":"})
    path = put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n0,0,0\n", "s.csv")
    with pytest.raises(ReaderOptionsError) as read:
        registry.read(path, "stations", reader="csv", options={"delimiter": ":"})
    (error,) = planned.value.errors()
    assert str(read.value) == f"options of reader 'csv': delimiter: {error['msg']}"
