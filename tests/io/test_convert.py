"""`gyropipe convert`: any readable input to the format of the output's extension, with
the same normalisation as a pipeline's readers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pipeline.convert import convert, read_any
from pipeline.errors import InputFileError, InputFileWarning, WrongKindError
from pipeline.plugins import load_registry
from pipeline.tables import RawSamples, Stations
from pipeline.well import WellMetadata
from tests_support import ROOT, gyropipe_cli

SAMPLE = ROOT / "examples" / "stations-j-well.csv"


def test_stations_csv_to_parquet_and_back(tmp_path: Path):
    out = tmp_path / "st.parquet"
    result = gyropipe_cli("convert", str(SAMPLE), str(out))
    assert result.returncode == 0, result.stderr
    table = pq.read_table(out)
    Stations.validate_table(table)
    assert "source_line" not in table.column_names
    assert table.schema.field("azi").metadata[b"north_reference"] == b"true"
    back = tmp_path / "st.csv"
    assert gyropipe_cli("convert", str(out), str(back)).returncode == 0
    again, well = read_any(load_registry(), back, kind="stations", reader="auto", options={})
    for name in ("md", "inc", "azi"):
        np.testing.assert_array_equal(again.column(name).to_numpy(), table.column(name).to_numpy())
    assert well.well == "J-12" and well.latitude == 61.25


def test_stations_through_las(tmp_path: Path):
    las = tmp_path / "st.las"
    result = gyropipe_cli("convert", str(SAMPLE), str(las))
    assert result.returncode == 0, result.stderr
    assert las.read_text().startswith("~V")
    table, well = read_any(load_registry(), las, kind="auto", reader="auto", options={})
    original, _ = read_any(load_registry(), SAMPLE, kind="stations", reader="auto", options={})
    for name in ("md", "inc", "azi"):
        np.testing.assert_array_equal(
            table.column(name).to_numpy(), original.column(name).to_numpy()
        )
    assert well.well == "J-12" and well.north_reference == "true"


def test_feet_are_converted_on_the_way(tmp_path: Path):
    src = tmp_path / "ft.csv"
    src.write_text("MD (ft),Inc (deg),Azimuth Grid (deg)\n0,0,0\n1000,2,45\n")
    table = convert(load_registry(), src, tmp_path / "m.parquet").table
    np.testing.assert_allclose(table.column("md").to_numpy(), [0.0, 304.8])
    assert pq.read_table(tmp_path / "m.parquet").schema.field("md").metadata[b"unit"] == b"m"


def test_samples_to_mcap_round_trip(tmp_path: Path):
    plan = ROOT / "examples" / "plans" / "vertical.yaml"
    gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "sim"), check=True)
    samples = tmp_path / "sim" / "samples.parquet"
    out = tmp_path / "samples.mcap"
    result = gyropipe_cli("convert", str(samples), str(out), "--kind", "samples")
    assert result.returncode == 0, result.stderr
    back, well = read_any(load_registry(), out, kind="samples", reader="auto", options={})
    RawSamples.validate_table(back)
    original = pq.read_table(samples)
    for name in original.column_names:
        assert back.column(name).to_pylist() == original.column(name).to_pylist(), name
    assert well.latitude == 61.25


def test_errors(tmp_path: Path):
    unknown = gyropipe_cli("convert", str(SAMPLE), str(tmp_path / "x.xlsx"))
    assert unknown.returncode == 2 and "no writer for 'x.xlsx'" in unknown.stderr
    missing = gyropipe_cli("convert", str(tmp_path / "nope.csv"), str(tmp_path / "x.parquet"))
    assert missing.returncode == 1 and "no such file" in missing.stderr
    garbage = tmp_path / "garbage.csv"
    garbage.write_bytes(b"\x00\x01\x02 not a survey")
    bad = gyropipe_cli("convert", str(garbage), str(tmp_path / "g.parquet"))
    assert bad.returncode == 1 and "a csv file that reads as none of stations" in bad.stderr
    assert not (tmp_path / "g.parquet").exists()
    assert "Traceback" not in bad.stderr


@pytest.mark.parametrize("option", ["units={md: ft}", "north_reference=grid"])
def test_reader_options_pass_through(tmp_path: Path, option: str):
    src = tmp_path / "bare.csv"
    src.write_text(
        "MD,Inc (deg),Azi (deg)\n0,0,0\n100,1,10\n"
        if "units" in option
        else "MD (m),Inc (deg),Azi (deg)\n0,0,0\n100,1,10\n"
    )
    extra = ["--option", "north_reference=true"] if "units" in option else []
    result = gyropipe_cli(
        "convert", str(src), str(tmp_path / "o.parquet"), "--option", option, *extra
    )
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize(
    ("cell", "shown"),
    [("-1e999", "'-1e999'"), ("1E+400", "'1E+400'"), ("9" * 400, "(400 characters)")],
)
def test_an_overflowing_number_is_refused_like_nan(tmp_path: Path, cell: str, shown: str):
    """A cell too large for a float (±inf) is a located error, as ``nan`` is (fuzz)."""
    src = tmp_path / "inf.csv"
    src.write_text(f"MD[m],INC[deg],Azimuth True[deg]\n0,0,0\n100,1,{cell}\n200,2,3\n")
    out = tmp_path / "o.parquet"
    result = gyropipe_cli("convert", str(src), str(out), "--kind", "stations")
    assert result.returncode == 1, result.stderr
    assert f"{src}:3 (column 'Azimuth True[deg]'): expected a finite number" in result.stderr
    assert shown in result.stderr
    assert not out.exists()
    src.write_text("MD[m],INC[deg],Azimuth True[deg]\n0,0,0\n100,1,nan\n200,2,3\n")
    nan = gyropipe_cli("convert", str(src), str(out), "--kind", "stations")
    assert nan.returncode == 1 and f"{src}:3 (column 'Azimuth True[deg]')" in nan.stderr


# ------------------------------------------- a table breaking its kind's contract (fuzz)


def _stations(inc: list[float]) -> pa.Table:
    return Stations.compiled().make_table(
        {"md": [0.0, 30.0, 60.0][: len(inc)], "inc": inc, "azi": [0.0, 10.0, 20.0][: len(inc)]},
        north_reference="true",
    )


def _samples() -> pa.Table:
    n = 5
    return RawSamples.compiled().make_table(
        {
            "time": [i * 0.01 for i in range(n)],
            "gyro_x": [1.0] * n,
            "acc_x": [0.0] * n,
            "acc_y": [0.0] * n,
            "acc_z": [9.81] * n,
        }
    )


def _written(tmp_path: Path, writer: str, table: pa.Table, name: str) -> Path:
    path = tmp_path / name
    load_registry().writers[writer][0].write(table, path, WellMetadata(north_reference="true"))
    return path


def _with_unit(table: pa.Table, column: str, unit: str) -> pa.Table:
    i = table.column_names.index(column)
    field = table.schema.field(i)
    return table.set_column(
        i, field.with_metadata({**field.metadata, b"unit": unit.encode()}), table.column(i)
    )


def _md_out_of_order(tmp_path: Path) -> tuple[Path, str]:
    path = tmp_path / "st.csv"
    path.write_text("MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n60,1,10\n30,2,20\n")
    return path, ":4: not valid as stations (reader 'csv'): column 'md': monotonic"


def _inc_huge(tmp_path: Path) -> tuple[Path, str]:
    path = tmp_path / "st.csv"
    path.write_text("MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n30,1e308,10\n")
    return (
        path,
        ":3 (column 'inc'): inclination 1e+308° is outside [0, 180]",  # pipeline.plausibility
    )


def _witsml_radians(tmp_path: Path) -> tuple[Path, str]:
    path = _written(tmp_path, "witsml", _stations([0.0, 2.0, 10.0]), "st.xml")
    text = path.read_text()
    assert text.count('<incl uom="dega">') == 3
    text = text.replace('<incl uom="dega">', '<incl uom="rad">')
    path.write_text(text)
    line = next(n for n, t in enumerate(text.splitlines(), 1) if '"rad">10.0<' in t)
    station = next(
        n for n in range(line, 0, -1) if "<trajectoryStation" in text.splitlines()[n - 1]
    )
    return path, f":{station} (column 'inc'): inclination 572.957795130823"


def _parquet_unit(tmp_path: Path) -> tuple[Path, str]:
    path = tmp_path / "st.parquet"
    pq.write_table(_with_unit(_stations([0.0, 1.0, 2.0]), "inc", "mg"), path)
    return path, "not valid as stations (reader 'parquet'): column 'inc': unit: expected unit 'deg'"


def _mcap_unit(tmp_path: Path) -> tuple[Path, str]:
    path = _written(tmp_path, "mcap", _with_unit(_samples(), "acc_z", ""), "s.mcap")
    return path, "not valid as samples (reader 'mcap'): column 'acc_z': unit"


def _las_time_back(tmp_path: Path) -> tuple[Path, str]:
    path = _written(tmp_path, "las", _samples(), "s.las")
    lines = path.read_text().splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if line.startswith("~A")) + 1
    lines[first + 2], lines[first + 3] = lines[first + 3], lines[first + 2]
    path.write_text("".join(lines))
    return path, f":{first + 4}: not valid as samples (reader 'las'): column 'time': monotonic"


@pytest.mark.parametrize(
    "make",
    [_md_out_of_order, _inc_huge, _witsml_radians, _parquet_unit, _mcap_unit, _las_time_back],
    ids=[
        "csv-md-order",
        "csv-inc-1e308",
        "witsml-radians",
        "parquet-unit",
        "mcap-unit",
        "las-time",
    ],
)
def test_a_table_breaking_its_contract_is_refused_when_read(tmp_path: Path, make) -> None:
    """Fuzz findings: readers let these through and ``gyropipe convert`` (and ``gp.read``,
    and a plan's stations file) took them: the engine checks every table read against its
    kind's contract, a failure located at the file and the line of its first bad row."""
    path, expected = make(tmp_path)
    out = tmp_path / "out.parquet"
    with pytest.raises(InputFileError) as info:
        convert(load_registry(), path, out)
    text = str(info.value)
    assert text.startswith(f"{path}{expected}" if expected[0] == ":" else f"{path}: {expected}")
    assert "\n" not in text
    assert not out.exists()


def test_a_table_of_another_kind_is_the_wrong_kind(tmp_path: Path) -> None:
    """A Parquet log asked for as stations was returned without md, inc, azi (and written)."""
    log = tmp_path / "log.parquet"
    pq.write_table(pa.table({"DEPT": [1.0, 2.0], "GR": [50.0, 60.0]}), log)
    with pytest.raises(
        WrongKindError, match=r"not stations: no column 'md', 'inc', 'azi'.*--kind log"
    ):
        convert(load_registry(), log, tmp_path / "o.csv", kind="stations")
    table = convert(load_registry(), log, tmp_path / "o.csv").table
    assert table.column_names == ["DEPT", "GR"]


def test_a_table_the_output_format_cannot_hold_names_the_files(tmp_path: Path) -> None:
    """Fuzz finding: a LAS log with no curve (or a null in its index) reads as a log, but
    the LAS writer cannot write it; the error (exit 2) named neither file."""
    src = tmp_path / "bare.las"
    src.write_text("~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.M 0 :\n WELL. W-1 :\n")
    out = tmp_path / "o.las"
    with (
        pytest.warns(InputFileWarning, match="no ~A"),
        pytest.raises(ValueError, match="no numeric column to write") as info,
    ):
        convert(load_registry(), src, out, kind="log")
    assert str(info.value).startswith(f"{src}: the log read cannot be written to o.las")
    assert not out.exists()
    result = gyropipe_cli("convert", str(src), str(out), "--kind", "log")
    assert result.returncode == 2 and "Traceback" not in result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert errors == [f"error: {info.value}"], result.stderr
