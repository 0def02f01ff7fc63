"""`gyropipe convert`: any readable input to the format of the output's extension, with
the same normalisation as a pipeline's readers."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pipeline.convert import convert_file, read_any
from pipeline.plugins import load_registry
from pipeline.tables import RawSamples, Stations
from tests_support import ROOT, gyropipe

SAMPLE = ROOT / "examples" / "stations-j-well.csv"


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*gyropipe(), "convert", *args], capture_output=True, text=True, cwd=ROOT, timeout=120
    )


def test_stations_csv_to_parquet_and_back(tmp_path: Path):
    out = tmp_path / "st.parquet"
    result = cli(str(SAMPLE), str(out))
    assert result.returncode == 0, result.stderr
    table = pq.read_table(out)
    Stations.validate_table(table)
    assert "source_line" not in table.column_names
    assert table.schema.field("azi").metadata[b"north_reference"] == b"true"
    back = tmp_path / "st.csv"
    assert cli(str(out), str(back)).returncode == 0
    again, well = read_any(load_registry(), back, kind="stations", reader="auto", options={})
    for name in ("md", "inc", "azi"):
        np.testing.assert_array_equal(again.column(name).to_numpy(), table.column(name).to_numpy())
    assert well.well == "J-12" and well.latitude == 61.25


def test_stations_through_las(tmp_path: Path):
    las = tmp_path / "st.las"
    result = cli(str(SAMPLE), str(las))
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
    table, _ = convert_file(load_registry(), src, tmp_path / "m.parquet")
    np.testing.assert_allclose(table.column("md").to_numpy(), [0.0, 304.8])
    assert pq.read_table(tmp_path / "m.parquet").schema.field("md").metadata[b"unit"] == b"m"


def test_samples_to_mcap_round_trip(tmp_path: Path):
    plan = ROOT / "examples" / "plans" / "vertical.yaml"
    subprocess.run(
        [*gyropipe(), "simulate", str(plan), "--out", str(tmp_path / "sim")],
        check=True,
        capture_output=True,
    )
    samples = tmp_path / "sim" / "samples.parquet"
    out = tmp_path / "samples.mcap"
    result = cli(str(samples), str(out), "--kind", "samples")
    assert result.returncode == 0, result.stderr
    back, well = read_any(load_registry(), out, kind="samples", reader="auto", options={})
    RawSamples.validate_table(back)
    original = pq.read_table(samples)
    for name in original.column_names:
        assert back.column(name).to_pylist() == original.column(name).to_pylist(), name
    assert well.latitude == 61.25


def test_errors(tmp_path: Path):
    unknown = cli(str(SAMPLE), str(tmp_path / "x.xlsx"))
    assert unknown.returncode == 2 and "no writer for 'x.xlsx'" in unknown.stderr
    missing = cli(str(tmp_path / "nope.csv"), str(tmp_path / "x.parquet"))
    assert missing.returncode == 1 and "no such file" in missing.stderr
    garbage = tmp_path / "garbage.csv"
    garbage.write_bytes(b"\x00\x01\x02 not a survey")
    bad = cli(str(garbage), str(tmp_path / "g.parquet"))
    assert bad.returncode == 1 and "cannot be read" in bad.stderr
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
    result = cli(str(src), str(tmp_path / "o.parquet"), "--option", option, *extra)
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
    result = cli(str(src), str(out), "--kind", "stations")
    assert result.returncode == 1, result.stderr
    assert f"{src}:3 (column 'Azimuth True[deg]'): expected a finite number" in result.stderr
    assert shown in result.stderr
    assert not out.exists()
    src.write_text("MD[m],INC[deg],Azimuth True[deg]\n0,0,0\n100,1,nan\n200,2,3\n")
    nan = cli(str(src), str(out), "--kind", "stations")
    assert nan.returncode == 1 and f"{src}:3 (column 'Azimuth True[deg]')" in nan.stderr
