"""The CSV reader's ``samples`` kind (RawSamples) on real files: header mnemonics, units from
the header or the options, vendor conventions, optional and integer columns, every error,
writer → reader round trips of simulator output, and a mutation fuzz test."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.contracts import UNIT_KEY
from pipeline.errors import InputFileError, UnitError
from pipeline.io import csv as csv_plugin
from pipeline.io.csv import rows as csv_rows
from pipeline.io.precision import DECIMALS
from pipeline.plugins import load_registry
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata
from tests_support import assert_exported, line_ops, mutate_lines, plugin_io

READER, WRITER = plugin_io(csv_plugin)
G = 9.80665


def put(tmp_path: Path, content: str | bytes, name: str = "samples.csv") -> Path:
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def read(path: Path, **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, "samples", READER.options.model_validate(options))


def column(table: pa.Table, name: str) -> list[Any]:
    return list(table.column(name).to_pylist())


def failure(path: Path, **options: Any) -> InputFileError:
    with pytest.raises(InputFileError) as info:
        read(path, **options)
    return info.value


HEADER = (
    "time [s],gyro_x [deg/h],gyro_y [deg/h],gyro_z [deg/h],acc_x [m/s2],acc_y [m/s2],acc_z [m/s2]"
)
BODY = "0,1,2,3,0.1,0.2,9.8\n0.01,4,5,6,0.3,0.4,9.7\n"


def test_plain_samples(tmp_path: Path) -> None:
    table, well = read(put(tmp_path, HEADER + "\n" + BODY))
    assert table.column_names == [
        *("time", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"),
        "source_line",
    ]
    assert column(table, "time") == [0.0, 0.01]
    assert column(table, "gyro_z") == [3.0, 6.0]
    assert column(table, "acc_z") == [9.8, 9.7]
    assert column(table, "source_line") == [2, 3]
    assert well == WellMetadata()
    RawSamples.validate_table(table)
    assert table.schema.field("gyro_x").metadata[UNIT_KEY] == b"deg/h"
    assert table.schema.field("acc_x").metadata[UNIT_KEY] == b"m/s2"


@pytest.mark.parametrize(
    ("header", "scale"),
    [
        (
            "TIME (s),GYRO X (deg/s),GYRO Y (deg/s),GYRO Z (deg/s),ACC X (g),ACC Y (g),ACC Z (g)",
            (3600.0, G),
        ),
        (
            "Elapsed Time [sec];WX [deg/hr];WY [deg/hr];WZ [deg/hr];GX [m/s^2];GY [m/s^2];GZ [m/s^2]",
            (1.0, 1.0),
        ),
        (
            "ETIM [s]|Rate X [rad/s]|Rate Y [rad/s]|Rate Z [rad/s]|Accel X [g]|Accel Y [g]|Accel Z [g]",
            (math.degrees(1.0) * 3600.0, G),
        ),
        (
            "tim (min)\tomega_x (°/h)\tomega_y (°/h)\tomega_z (°/h)\taccx (g)\taccy (g)\taccz (g)",
            (1.0, G),
        ),
    ],
)
def test_header_mnemonics_and_units(
    tmp_path: Path, header: str, scale: tuple[float, float]
) -> None:
    delimiter = next(d for d in ";|\t," if d in header)
    body = BODY.replace(",", delimiter)
    table, _ = read(put(tmp_path, header + "\n" + body))
    rate, accel = scale
    time_scale = 60.0 if "min" in header else 1.0
    assert column(table, "time") == [0.0, 0.01 * time_scale]
    assert column(table, "gyro_x") == [1.0 * rate, 4.0 * rate]
    assert column(table, "acc_z") == [9.8 * accel, 9.7 * accel]


def test_magnetometers_and_optional_columns(tmp_path: Path) -> None:
    text = (
        "Time[s],MD[ft],Frame Angle[deg],Gyro X[deg/h],GX[m/s2],GY[m/s2],GZ[m/s2],"
        "Mag X[uT],Mag Y[uT],Mag Z[gauss],Station,Position\n"
        "0,100,0,1,0,0,9.8,10,-20,0.5,0,\n"
        "1,100.5,90,2,0,0,9.8,11,-21,0.6,,1\n"
    )
    table, _ = read(put(tmp_path, text))
    assert column(table, "md") == [30.48, 100.5 * 0.3048]
    assert column(table, "frame_angle") == [0.0, 90.0]
    assert column(table, "mag_x") == [10_000.0, 11_000.0]
    assert column(table, "mag_z") == [50_000.0, 60_000.0]
    assert column(table, "station") == [0, None]
    assert column(table, "position") == [None, 1]
    assert table.schema.field("station").type == pa.int64()
    assert "gyro_y" not in table.column_names  # a single-axis gyro
    RawSamples.validate_table(table)


def test_units_option_and_shared_column_names(tmp_path: Path) -> None:
    text = "t,w x,w y,w z,g x,g y,g z\n0,1,1,1,0,0,1\n"
    options = {"columns": {"time": "t"}, "units": {"time": "s", "gyro_x": "deg/s"}}
    units = dict.fromkeys(["gyro_y", "gyro_z"], "deg/h") | dict.fromkeys(
        ["acc_x", "acc_y", "acc_z"], "g"
    )
    table, _ = read(put(tmp_path, text), **options | {"units": options["units"] | units})
    assert column(table, "gyro_x") == [3600.0]
    assert column(table, "gyro_y") == [1.0]
    assert column(table, "acc_z") == [G]


def test_units_option_overrides_the_header(tmp_path: Path) -> None:
    table, _ = read(put(tmp_path, HEADER + "\n" + BODY), units={"gyro_x": "deg/s"})
    assert column(table, "gyro_x") == [3600.0, 4 * 3600.0]
    assert column(table, "gyro_y") == [2.0, 5.0]


def test_conventions_are_applied(tmp_path: Path) -> None:
    conventions = {
        "axes": ["y", "-x", "z"],
        "accelerometer": "specific_force",
        "gyro_rotation": "left_hand",
        "frame_angle_direction": "counterclockwise",
    }
    text = HEADER + ",frame_angle [deg]\n0,1,2,3,0.1,0.2,-9.8,90\n"
    table, _ = read(put(tmp_path, text), conventions=conventions)
    assert [column(table, f"gyro_{a}")[0] for a in "xyz"] == [-2.0, 1.0, -3.0]
    assert [column(table, f"acc_{a}")[0] for a in "xyz"] == [-0.2, 0.1, 9.8]
    assert column(table, "frame_angle") == [270.0]
    assert table.schema.field("gyro_x").metadata[UNIT_KEY] == b"deg/h"


def test_conventions_that_mix_axes_need_whole_triads(tmp_path: Path) -> None:
    text = "time[s],gyro_x[deg/h],acc_x[g],acc_y[g],acc_z[g]\n0,1,0,0,1\n"
    err = failure(put(tmp_path, text), conventions={"axes": ["y", "x", "-z"]})
    assert err.line == 1
    assert "option conventions" in str(err)
    assert "gyro needs columns" in str(err)


def test_blank_and_comment_lines_keep_line_numbers(tmp_path: Path) -> None:
    rows = BODY.splitlines()
    text = f"# log\n{HEADER}\n\n{rows[0]}\n   \n# pause\n\t# note\n{rows[1]}\nEnd of log\n"
    table, _ = read(put(tmp_path, text))
    assert column(table, "time") == [0.0, 0.01]
    assert column(table, "source_line") == [4, 8]


def test_commented_out_row_is_skipped(tmp_path: Path) -> None:
    text = "Note,time[s],wx[deg/h],gx[g],gy[g],gz[g]\na,0,1,0,0,1\n#b,1,1,0,0,1\nc,2,1,0,0,1\n"
    table, _ = read(put(tmp_path, text))
    assert column(table, "time") == [0.0, 2.0]
    assert column(table, "source_line") == [2, 4]


def test_decimal_commas(tmp_path: Path) -> None:
    text = HEADER.replace(",", ";") + "\n" + "0;1,5;2;3;0,1;0,2;9,8\n1;4;5;6;0,3;0,4;9,7\n"
    table, _ = read(put(tmp_path, text))
    assert column(table, "gyro_x") == [1.5, 4.0]
    assert column(table, "acc_z") == [9.8, 9.7]


def test_title_block_well_metadata(tmp_path: Path) -> None:
    text = "Gyro log\nWell: A-12\nSerial: SN-7\n" + HEADER + "\n" + BODY
    _, well = read(put(tmp_path, text))
    assert well == WellMetadata(well="A-12", tool_serial="SN-7")


# ------------------------------------------------------------------------ round trip


def _simulation(tool: dict[str, Any]) -> pa.Table:
    spec = SimulationSpec.model_validate(
        {
            "name": "t",
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
                    {"kind": "vertical", "length": 10},
                    {"kind": "curve", "dls": 30.0, "inc": 20, "azi": 40},
                ]
            },
            "tool": tool,
            "survey": {"mode": "point", "every": 10, "dwell": 1.0, "move_time": 0.5, "speed": 5},
        }
    )
    samples: pa.Table = simulate(spec).samples
    return samples


@pytest.mark.parametrize("tool", [{"preset": "ideal"}, {"preset": "mems-vrg"}])
def test_simulator_samples_round_trip(tmp_path: Path, tool: dict[str, Any]) -> None:
    samples = _simulation(tool)
    assert samples.column("station").null_count and samples.column("position").null_count
    well = WellMetadata(well="A-12", latitude=61.25, tool_type="gyro, MEMS", survey_date=None)
    path = tmp_path / "samples.csv"
    WRITER.write(samples, path, well)
    back, read_well = read(path)
    assert read_well == well
    assert back.column_names == [*samples.column_names, "source_line"]
    for field in samples.schema:
        got = back.schema.field(field.name)
        assert (got.type, got.metadata) == (field.type, field.metadata), field.name
    assert_exported(back, samples)
    RawSamples.validate_table(back)


def test_floats_are_written_to_their_units_step(tmp_path: Path) -> None:
    """Each float is written rounded to its unit's step (DECIMALS), whatever its magnitude:
    read back, it is within half a step of the value and a whole number of steps, and its
    cell shows no more decimals."""
    rng = np.random.default_rng(3)
    values = {
        name: rng.normal(0, 1e3, 500) * 10.0 ** rng.integers(-300, 300, 500)
        for name in ("gyro_x", "acc_x", "acc_y", "acc_z")
    }
    table = RawSamples.compiled().make_table({"time": np.arange(500.0) / 3} | values)
    path = tmp_path / "rounded.csv"
    WRITER.write(table, path, WellMetadata())
    back, _ = read(path)
    assert_exported(back, table)
    cells = [line.split(",") for line in path.read_text().splitlines()[2:]]
    header = path.read_text().splitlines()[1].split(",")
    for name in ["time", *values]:
        unit = table.schema.field(name).metadata[UNIT_KEY].decode()
        decimals = DECIMALS[unit]
        assert all(round(v, decimals) == v for v in back.column(name).to_pylist()), name
        at = next(i for i, h in enumerate(header) if h.startswith(f"{name}["))
        for row in cells:
            number, _, exponent = row[at].partition("e")
            assert len(number.partition(".")[2]) - int(exponent or 0) <= decimals, row[at]


def test_an_angle_just_below_a_full_turn_is_written_below_it(tmp_path: Path) -> None:
    """Rounded to its 1e-6° step, 359.9999997° would be written 360, which the samples
    contract refuses (frame angles are [0, 360)): it is written one step under, and the file
    reads back."""
    angles = np.array([0.0, 359.9999997, 359.9999994, 180.0000004])
    table = RawSamples.compiled().make_table(
        {
            "time": np.arange(4.0),
            "gyro_x": np.zeros(4),
            "acc_x": np.zeros(4),
            "acc_y": np.zeros(4),
            "acc_z": np.full(4, G),
            "frame_angle": angles,
        }
    )
    path = tmp_path / "turn.csv"
    WRITER.write(table, path, WellMetadata())
    back, _ = read(path)
    RawSamples.validate_table(back)
    assert column(back, "frame_angle") == [0.0, 359.999999, 359.999999, 180.0]


def test_unlisted_unit_floats_round_trip_exactly(tmp_path: Path) -> None:
    """A float column whose unit has no DECIMALS entry (or no unit) is written in shortest
    round-trip form: read back bit for bit, whatever its magnitude."""
    rng = np.random.default_rng(4)
    values = rng.normal(0, 1e3, 500) * 10.0 ** rng.integers(-300, 300, 500)
    assert "ft" not in DECIMALS
    schema = pa.schema(
        [pa.field("ratio", pa.float64()), pa.field("x", pa.float64(), metadata={UNIT_KEY: b"ft"})]
    )
    table = pa.table({"ratio": values, "x": values[::-1]}, schema=schema)
    path = tmp_path / "exact.csv"
    WRITER.write(table, path, WellMetadata())
    back = pacsv.read_csv(path, pacsv.ReadOptions(skip_rows=1))
    for name, written in zip(("ratio", "x[ft]"), table.columns, strict=True):
        assert np.array_equal(
            back.column(name).to_numpy().view(np.int64), written.to_numpy().view(np.int64)
        ), name


@pytest.mark.parametrize(
    "text",
    [
        HEADER + "\n" + BODY,
        (HEADER + "\n" + BODY).replace("\n", "\r\n"),
        f"# log\n{HEADER}\n\n{BODY.replace(chr(10), chr(10) + '# note' + chr(10), 1)}\n",
        HEADER.replace(",", ";") + "\n" + "0;1,5;2;3;0,1;0,2;9,8\n",
    ],
)
def test_clean_files_are_parsed_typed_on_all_cores(
    tmp_path: Path, text: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Large logs stay fast: valid files never fall back to the one-thread string parse."""

    def slow(*args: Any) -> None:
        raise AssertionError("fell back to the string parse")

    monkeypatch.setattr(csv_rows, "_strings", slow)
    table, _ = read(put(tmp_path, text))
    assert table.num_rows >= 1


# --------------------------------------------------------------------------- errors


def test_missing_required_column(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "Log\ntime[s],gyro_x[deg/h],acc_x[g],acc_y[g]\n0,1,2,3\n"))
    assert err.line == 2
    assert "missing column(s) acc_z" in str(err)


def test_no_header(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "1,2,3\n"))
    assert "no header row with time, gyro_x, acc_x, acc_y, acc_z columns" in str(err)
    assert "ELAPSED TIME" in str(err)


@pytest.mark.parametrize("cell", ["time [s]", "gyro_x [deg/h]", "acc_y [m/s2]"])
def test_column_without_unit(tmp_path: Path, cell: str) -> None:
    bare = cell.split(" [")[0]
    err = failure(put(tmp_path, HEADER.replace(cell, bare) + "\n" + BODY))
    assert (err.line, err.column) == (1, bare)
    assert "no unit for this column" in str(err)
    assert re.search(rf"reader option units: \{{{bare}: [^}}…]+\}}", str(err))  # a working form


@pytest.mark.parametrize(
    ("unit", "message"),
    [("furlong/s", "unknown unit 'furlong/s'"), ("m/s2", "unit 'm/s2' is an acceleration")],
)
def test_bad_header_unit(tmp_path: Path, unit: str, message: str) -> None:
    err = failure(put(tmp_path, HEADER.replace("gyro_z [deg/h]", f"gyro_z [{unit}]") + "\n" + BODY))
    assert err.column == f"gyro_z [{unit}]"
    assert message in str(err)


def test_bad_unit_option() -> None:
    with pytest.raises(ValueError, match=r"gyro_x: unit 'm' is a length, expected an angular rate"):
        READER.options.model_validate({"units": {"gyro_x": "m"}})
    with pytest.raises(ValueError, match="unknown column 'gyro_q'"):
        READER.options.model_validate({"units": {"gyro_q": "deg/h"}})
    with pytest.raises(ValueError, match="column 'station' has no unit"):
        READER.options.model_validate({"units": {"station": "m"}})


@pytest.mark.parametrize(
    ("row", "col", "message"),
    [
        (",1,2,3,0.1,0.2,9.8", "time [s]", "got an empty cell"),
        ("0.02,1,2,x,0.1,0.2,9.8", "gyro_z [deg/h]", "got 'x'"),
        ("0.02,1,2,3,0.1,nan,9.8", "acc_y [m/s2]", "got 'nan'"),
        ("0.02,1,2,3,0.1,0.2,", "acc_z [m/s2]", "got an empty cell"),
    ],
)
def test_bad_cell(tmp_path: Path, row: str, col: str, message: str) -> None:
    err = failure(put(tmp_path, HEADER + "\n" + BODY + row + "\n0.03,1,2,3,0.1,0.2,9.8\n"))
    assert (err.line, err.column) == (4, col)
    assert message in str(err)


def test_an_empty_cell_is_null_where_the_contract_allows_it(tmp_path: Path) -> None:
    """md may be null (no odometer reading); a required column's empty cell is an error."""
    text = "time[s],md[m],wx[deg/h],gx[g],gy[g],gz[g]\n0,1,1,0,0,1\n1,,1,0,0,1\n"
    table, _ = read(put(tmp_path, text))
    assert table.column("md").to_pylist() == [1.0, None]
    err = failure(put(tmp_path, text.replace("1,,1,0,0,1", "1,2,1,0,,1")))
    assert (err.line, err.column) == (3, "gy[g]")


@pytest.mark.parametrize("column", ["md", "frame_angle", "gyro_y", "mag_x", "station"])
def test_nulls_the_writer_writes_read_back(tmp_path: Path, column: str) -> None:
    """Fuzz finding: a samples table with a null frame_angle (valid: MCAP and Parquet carry
    it) was written as an empty cell that the reader refused, so ``gyropipe convert``'s CSV
    of it could not be read back."""
    n = 4
    data: dict[str, list[Any]] = {
        "time": [0.0, 0.01, 0.02, 0.03],
        "md": [1.0] * n,
        "frame_angle": [0.0] * n,
        "gyro_x": [1.0] * n,
        "gyro_y": [2.0] * n,
        "acc_x": [0.0] * n,
        "acc_y": [0.0] * n,
        "acc_z": [9.8] * n,
        "mag_x": [1.0] * n,
        "station": [0] * n,
    }
    data[column][2] = None
    table = RawSamples.compiled().make_table(data)
    RawSamples.validate_table(table)
    path = tmp_path / "nulls.csv"
    WRITER.write(table, path, WellMetadata())
    back, _ = read(path)
    assert back.drop_columns("source_line").equals(table)


def test_bad_integer(tmp_path: Path) -> None:
    text = "time[s],wx[deg/h],gx[g],gy[g],gz[g],station\n0,1,0,0,1,1\n1,1,0,0,1,1.5\n"
    err = failure(put(tmp_path, text))
    assert (err.line, err.column) == (3, "station")
    assert "expected an integer, got '1.5'" in str(err)


def test_wrong_cell_count(tmp_path: Path) -> None:
    rows = "".join(f"{i},1,2,3,4,5,6\n" for i in range(50)) + "50,1,2,3\n51,1,2,3,4,5,6\n"
    err = failure(put(tmp_path, "# log\n\n" + HEADER + "\n" + rows))
    assert err.line == 54
    assert "expected 7 cells as in the header (line 3), got 4" in str(err)


def test_invalid_utf8(tmp_path: Path) -> None:
    err = failure(put(tmp_path, (HEADER + "\n" + BODY).encode() + b"1,\xe9,2,3,4,5,6\n"))
    assert err.line == 4
    assert "not UTF-8" in str(err)


def test_crlf_and_bom(tmp_path: Path) -> None:
    text = "\ufeff" + (HEADER + "\n" + BODY).replace("\n", "\r\n")
    table, _ = read(put(tmp_path, text))
    assert column(table, "source_line") == [2, 3]


def test_sniff_and_choice(tmp_path: Path) -> None:
    path = put(tmp_path, "Log\n" + HEADER.replace(",", ";") + "\n0;1;2;3;4;5;6\n", "log.dat")
    assert READER.sniff(path)
    assert load_registry().reader_for(path, "samples").name == "csv"
    assert not READER.sniff(put(tmp_path, "a;b;c\n1;2;3\n", "other.dat"))


# ----------------------------------------------------------------------------- fuzz

VALID = (
    b"Well: A-12\nTime [s];MD [ft];Gyro X [deg/s];Gyro Y [deg/s];ACC X [g];ACC Y [g];ACC Z [g];"
    b"Station\n0;100;0,001;-0,002;0,01;0,02;0,99;0\n0,01;100,5;0,003;0,001;0,01;0,02;0,98;\n"
    b"0,02;101;0,002;0,002;0,02;0,01;0,97;1\nEnd of log\n"
)


_op = line_ops()


def test_valid_fuzz_seed_parses(fuzz_dir: Path) -> None:
    table, well = read(put(fuzz_dir, VALID))
    assert column(table, "md") == [30.48, 100.5 * 0.3048, 101 * 0.3048]
    assert column(table, "gyro_x") == [3.6, 0.003 * 3600, 0.002 * 3600]
    assert column(table, "station") == [0, None, 1]
    assert well.well == "A-12"


def test_swapped_columns_read_the_same(fuzz_dir: Path) -> None:
    table, _ = read(put(fuzz_dir, VALID))
    swapped, _ = read(
        put(fuzz_dir, mutate_lines(VALID, [("swap", 7 * 3 + 1, 0)], b";"), "swapped.csv")
    )
    assert swapped.select(table.column_names).equals(table)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(ops=st.lists(_op, min_size=1, max_size=3))
def test_fuzz_mutations_raise_typed_errors_only(
    fuzz_dir: Path, ops: list[tuple[str, int, int]]
) -> None:
    path = put(fuzz_dir, mutate_lines(VALID, ops, b";"))
    try:
        table, _ = read(path)
    except (InputFileError, UnitError):
        return
    assert table.num_rows >= 1
    assert {"time", "gyro_x", "acc_x", "acc_y", "acc_z", "source_line"} <= set(table.column_names)
