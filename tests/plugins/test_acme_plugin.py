"""The example vendor adapter ``plugins/gyropipe-acme``, installed (offline: its package and
``.dist-info`` in a site directory, ``conftest.py``): found through its entry point,
simulator samples written as Acme GyroLog (Acme's units and axes) come back through a
pipeline equal to the simulator's, and a malformed file is reported by file and line. The
command line runs in process."""

from __future__ import annotations

import datetime as dt
import json
import textwrap
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import Result

from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.well import WellMetadata, well_of
from tests_support import ROOT

Cli = Callable[..., Result]
SPEC = {
    "name": "acme",
    "seed": 5,
    "site": {
        "latitude": 61.25,
        "longitude": 73.4,
        "elevation": 120.0,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
    },
    "well": {
        "sections": [
            {"kind": "vertical", "length": 20},
            {"kind": "curve", "dls": 30.0, "inc": 30, "azi": 40, "length": 40},
        ]
    },
    "tool": {"preset": "ideal"},
    "survey": {"mode": "point", "every": 25, "dwell": 2.0, "move_time": 1.0, "speed": 5.0},
}
WELL = WellMetadata(
    well="Acme-1",
    tool_serial="AG-1093",
    latitude=61.25,
    longitude=73.4,
    survey_date=dt.date(2026, 11, 21),
)
RTOL = 1e-14
"""The format keeps 15 significant digits (relative rounding ≤ 5e-15); the unit factors
add a few ulps (~1e-16 each). Every conversion is a scaling or a sign/axis swap, so the
error stays relative, zeros included."""
FRAME_ATOL = 1e-12
"""deg. The frame angle is stored reversed (360° − θ, rounded at 360°: ≤ 3e-14°) in rad in
[0, 2π) with 15 significant digits (≤ 5e-15 rad ≈ 3e-13°)."""
G0 = 9.80665  # m/s² per g
FT = 0.3048  # m per ft
PIPELINE = """
name: acme_ingest
version: "1"
inputs:
  samples: {description: Acme GyroLog raw samples}
stages:
  - id: read
    uses: read_samples
    with: {input: samples, reader: auto}
    persist: [samples]
"""


@pytest.fixture(scope="module")
def samples() -> pa.Table:
    """Raw samples of an ideal three-axis tool with magnetometers: three stations, each
    with five frame positions, about 5800 samples at 100 Hz."""
    return simulate(SimulationSpec.model_validate(SPEC)).samples


def vendor_columns(path: Path) -> dict[str, np.ndarray]:
    """The numeric channels of an Acme file, read by hand (independently of the plugin)."""
    lines = path.read_text().splitlines()
    names = next(line for line in lines if line.startswith("CHANNELS=")).split("=")[1].split()
    rows = [line.split() for line in lines[lines.index("DATA") + 1 :]]
    return {
        name: np.array([row[i] for row in rows], dtype=float)
        for i, name in enumerate(names)
        if name not in ("STN", "POS")
    }


def column(table: pa.Table, name: str) -> np.ndarray:
    return table.column(name).to_numpy(zero_copy_only=False)


def test_plugins_command_lists_acme(acme: ModuleType, cli: Cli):
    out = cli("plugins")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert (
        "acme 0.1.0 (third-party): reader:acme, reader:acme_survey, writer:acme, "
        "tool_model:ACME-GYRO-V2" in lines
    )
    assert (
        "  acme_survey (acme 0.1.0) reads stations: By content: the first line is the title "
        "``ACME SURVEY REPORT``." in lines
    )
    assert not [line for line in lines if line.startswith("problem:") and "acme" in line]


def test_vendor_tool_model_is_found_by_name(acme: ModuleType, cli: Cli):
    """The plugin's model file (GYRO-NS extended by a formula term) is listed and selected
    by name like a shipped one."""
    out = cli("models")
    assert out.returncode == 0, out.stderr
    assert any(
        line.startswith("ACME-GYRO-V2 ") and "acme-gyro-v2.yaml" in line
        for line in out.stdout.splitlines()
    )
    shown = cli("models", "acme-gyro-v2", "--json")
    assert shown.returncode == 0, shown.stderr
    doc = json.loads(shown.stdout)
    terms = {t["name"]: t for t in doc["terms"]}
    assert terms["ACME-THERM"]["weight"] == "formula"
    assert terms["GXY-RN"]["magnitude"] == 0.25 and terms["GXY-G4"]["magnitude"] == 0.6
    assert doc["needs"] == ["latitude"]


def test_pipeline_reads_acme_file_back_to_the_simulated_samples(
    acme: ModuleType, cli: Cli, samples: pa.Table, tmp_path: Path
):
    agl = tmp_path / "run.agl"
    acme.write_samples(samples, agl, WELL)

    # the file really is in Acme's units and axes: the format's definition, by hand
    vendor = vendor_columns(agl)
    expected = {
        "T": column(samples, "time"),
        "DEPTH": column(samples, "md") / FT,
        "WX": column(samples, "gyro_y") / 3600,  # deg/h → deg/s; Acme x = canonical y
        "WY": column(samples, "gyro_x") / 3600,
        "WZ": -column(samples, "gyro_z") / 3600,  # Acme z points up-hole
        "AX": -column(samples, "acc_y") / G0,  # m/s² → g; specific force: −g at rest
        "AY": -column(samples, "acc_x") / G0,
        "AZ": column(samples, "acc_z") / G0,  # up-hole and specific force: two sign flips
        "MX": column(samples, "mag_y") / 1000,  # nT → µT
        "MY": column(samples, "mag_x") / 1000,
        "MZ": -column(samples, "mag_z") / 1000,
    }
    for name, values in expected.items():
        np.testing.assert_allclose(vendor[name], values, rtol=RTOL, atol=0, err_msg=name)
    counterclockwise = np.radians((360.0 - column(samples, "frame_angle")) % 360.0)
    np.testing.assert_allclose(
        vendor["FANG"], counterclockwise, rtol=0, atol=np.radians(FRAME_ATOL)
    )
    assert vendor["AZ"][0] == pytest.approx(1.0, abs=3e-3)  # vertical at rest: +1 g up-hole

    spec = tmp_path / "acme.yaml"
    spec.write_text(textwrap.dedent(PIPELINE))
    out_dir = tmp_path / "out"
    result = cli("run", str(spec), "--input", str(agl), "--out", str(out_dir))
    assert result.returncode == 0, result.stderr
    manifest = json.loads((out_dir / "run.json").read_text())
    assert manifest["plugins"]["acme"] == "0.1.0"

    table = pq.read_table(out_dir / "read.samples.parquet")
    assert table.column_names == [*samples.column_names, "source_line"]
    for name in samples.column_names:
        field, truth = table.schema.field(name), samples.schema.field(name)
        assert field.type == truth.type, name
        assert (field.metadata or {}).get(b"unit") == (truth.metadata or {}).get(b"unit"), name
        if name in ("station", "position"):
            assert table.column(name).to_pylist() == samples.column(name).to_pylist(), name
        elif name == "frame_angle":
            diff = (column(table, name) - column(samples, name) + 180.0) % 360.0 - 180.0
            np.testing.assert_allclose(diff, 0.0, rtol=0, atol=FRAME_ATOL)
        else:
            np.testing.assert_allclose(
                column(table, name), column(samples, name), rtol=RTOL, atol=0, err_msg=name
            )
    units = {table.schema.field(n).metadata[b"unit"] for n in ("gyro_x", "acc_z", "mag_y", "md")}
    assert units == {b"deg/h", b"m/s2", b"nT", b"m"}
    header = agl.read_text().splitlines().index("DATA") + 1
    assert column(table, "source_line")[[0, -1]].tolist() == [header + 1, header + len(table)]
    well = well_of(table)
    assert well is not None
    assert (well.well, well.tool_serial, well.latitude, well.survey_date) == (
        "Acme-1",
        "AG-1093",
        61.25,
        dt.date(2026, 11, 21),
    )


@pytest.mark.parametrize(
    ("line", "edit", "message"),
    [
        (4, lambda text: "LAT=95", "LAT=95: Input should be less than or equal to 90"),
        (
            9,
            lambda text: text.replace(" ", " 1.2.3 ", 1).rsplit(" ", 1)[0],
            "(column 'DEPTH'): '1.2.3' is not a number",
        ),
        (12, lambda text: text.rsplit(" ", 3)[0], "11 values, expected 14"),
    ],
    ids=["header-value", "data-value", "short-row"],
)
def test_malformed_file_is_reported_by_file_and_line(
    acme: ModuleType, cli: Cli, samples: pa.Table, tmp_path: Path, line, edit, message
):
    agl = tmp_path / "bad.agl"
    acme.write_samples(samples.slice(0, 10), agl, WELL)
    lines = agl.read_text().splitlines()
    lines[line - 1] = edit(lines[line - 1])
    agl.write_text("\n".join(lines) + "\n")
    spec = tmp_path / "acme.yaml"
    spec.write_text(textwrap.dedent(PIPELINE))
    result = cli("run", str(spec), "--input", str(agl), "--out", str(tmp_path / "out"))
    assert result.returncode == 1, result.output
    assert "Traceback" not in result.stderr
    assert f"{agl}:{line}" in result.stderr
    assert message in result.stderr
    assert not (tmp_path / "out" / "read.samples.parquet").exists()


REPORT = """\
ACME SURVEY REPORT
WELL=Acme-2
NORTH=GRID
MD(ft) INC(deg) AZI(deg)
0.0 0.0 0.0
100.0 2.5 47.5
200.0 5.0 48.0
"""


def test_vendor_txt_reader_wins_over_the_builtin_csv_reader(
    acme: ModuleType, cli: Cli, tmp_path: Path
):
    """A .txt file with MD/INC/AZI in its header: the built-in CSV reader claims it by its
    name and fails on it (the plugin disabled); with the plugin its reader claims it by
    content and reads it (feet → m, grid north as the file declares, the well name from the
    header)."""
    report = tmp_path / "report.txt"
    report.write_text(REPORT)
    survey = ROOT / "pipelines" / "survey.yaml"
    args = ("run", str(survey), "--input", str(report), "--out")
    without = cli(*args, str(tmp_path / "a"), "--disable-plugin", "acme")
    assert without.returncode == 1
    assert "builtin.files" in without.stderr and "no header row with md, inc, azi" in without.stderr
    out = tmp_path / "b"
    result = cli(*args, str(out))
    assert result.returncode == 0, result.stderr
    table = pq.read_table(out / "trajectory.trajectory.parquet")
    assert column(table, "md").tolist() == [0.0, 30.48, 60.96]
    assert column(table, "inc").tolist() == [0.0, 2.5, 5.0]
    assert table.schema.field("azi").metadata[b"north_reference"] == b"grid"
    assert well_of(table).well == "Acme-2"


def test_a_failing_vendor_reader_is_named(acme: ModuleType, cli: Cli, tmp_path: Path):
    report = tmp_path / "report.txt"
    report.write_text(REPORT.replace("100.0 2.5 47.5", "100.0 2.5"))
    survey = ROOT / "pipelines" / "survey.yaml"
    result = cli("run", str(survey), "--input", str(report), "--out", str(tmp_path / "o"))
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert "reader 'acme_survey' (plugin acme 0.1.0) failed: InputFileError:" in result.stderr
    assert f"{report}:6: expected three numbers, got '100.0 2.5'" in result.stderr
