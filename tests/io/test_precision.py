"""Exports without float noise (:mod:`pipeline.io.precision`): each float column at its
unit's decimals, in the CSV and LAS a ready pipeline writes and in ``for_export`` itself."""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import pyarrow as pa

from pipeline.contracts import UNIT_KEY
from pipeline.io.precision import BLOCK_VALUES, DECIMALS, blocks, for_export
from pipeline.units import QUANTITIES
from tests_support import gyropipe_cli


def decimals(cell: str) -> int:
    """Decimals a number's text shows (``914.4`` 1, ``30`` 0, ``1.5e-07`` 8)."""
    float(cell)  # a number, or this raises
    mantissa, _, exponent = cell.lower().partition("e")
    return max(len(mantissa.partition(".")[2]) - int(exponent or 0), 0)


def test_every_canonical_unit_has_decimals() -> None:
    assert {q.canonical for q in QUANTITIES.values()} <= set(DECIMALS)


def test_survey_run_exports_hold_no_float_noise(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["run", "pipelines/survey.yaml", "--input", "examples/stations-j-well.csv"]
    run = gyropipe_cli(*args, "--out", str(out))
    assert run.returncode == 0, run.stderr

    lines = (out / "trajectory.csv").read_text().splitlines()
    rows = list(csv.reader(line for line in lines if not line.startswith("#")))
    header, body = rows[0], rows[1:]
    units = [re.fullmatch(r"(\w+)\[(.+)\]", cell) for cell in header]
    assert all(units) and body
    csv_rows = [dict(zip(header, row, strict=True)) for row in body]
    for row in csv_rows:
        for name, found in zip(header, units, strict=True):
            assert found is not None
            assert decimals(row[name]) <= DECIMALS[found[2]], (name, row[name])
    at_30 = next(row for row in csv_rows if row["md[m]"] == "30")
    assert at_30["tvd[m]"] == "30"  # not 29.999999847691296
    assert at_30["dls[deg/30m]"] == "0.01"  # not 0.010000000000000002

    text = (out / "trajectory.las").read_text()
    curves = text.split("~Curve")[1].split("~")[0].splitlines()[1:]
    las_units = [line.split(":")[0].strip().split(".", 1)[1].split()[0] for line in curves]
    ascii_rows = [line.split() for line in text.split("~ASCII")[1].splitlines()[1:]]
    assert ascii_rows and len(las_units) == len(ascii_rows[0]) == 11
    for row in ascii_rows:
        for unit, cell in zip(las_units, row, strict=True):
            assert decimals(cell) <= DECIMALS[unit], (unit, cell)
    assert ascii_rows[1][:4] == ["30", "0.01", "135.46", "30"]  # md inc azi tvd


def test_for_export_rounds_listed_units_and_leaves_the_rest() -> None:
    values = [914.4000000000001, 29.999999847691296, -1e-300, 1e300, math.nan, math.inf, None]
    fields = [
        pa.field("md", pa.float64(), metadata={UNIT_KEY: b"m", b"other": b"kept"}),
        pa.field("azi", pa.float32(), metadata={UNIT_KEY: b"deg"}),
        pa.field("gr", pa.float64(), metadata={UNIT_KEY: b"gAPI"}),
        pa.field("ratio", pa.float64()),
        pa.field("n", pa.int64(), metadata={UNIT_KEY: b"m"}),
    ]
    table = pa.table(
        [values, values, values, values, [1, 2, 3, 4, 5, 6, None]], schema=pa.schema(fields)
    )
    exported = for_export(table)
    assert exported.schema.equals(table.schema, check_metadata=True)
    md = exported.column("md").to_pylist()
    assert md[:4] == [914.4, 30.0, 0.0, 1e300] and math.copysign(1, md[2]) == 1  # no −0
    assert math.isnan(md[4]) and md[5:] == [math.inf, None]
    azi = exported.column("azi").to_pylist()
    assert azi[:3] == [pa.scalar(914.4, pa.float32()).as_py(), 30.0, 0.0]
    for name in ("gr", "ratio", "n"):  # unlisted unit, no unit, not floats: every bit kept
        assert list(map(repr, exported.column(name).to_pylist())) == list(
            map(repr, table.column(name).to_pylist())
        ), name


def test_columns_are_stacked_in_blocks_of_bounded_size() -> None:
    names = ["a", "b", "c", "d", "e"]
    assert list(blocks(names, 0)) == [names]  # no rows: every column in one block
    assert list(blocks(names, BLOCK_VALUES // 2)) == [["a", "b"], ["c", "d"], ["e"]]
    assert list(blocks(names, BLOCK_VALUES + 1)) == [[n] for n in names]  # long: one each
    assert list(blocks([], 10)) == []


def test_a_long_table_is_rounded_as_a_short_one() -> None:
    rows = BLOCK_VALUES // 2 + 1  # two columns exceed a block: rounded one by one
    field = pa.field("md", pa.float64(), metadata={UNIT_KEY: b"m"})
    angle = pa.field("azi", pa.float64(), metadata={UNIT_KEY: b"deg"})
    tvd = pa.field("tvd", pa.float64(), metadata={UNIT_KEY: b"m"})
    md = [914.4000000000001] * rows
    azi = [359.9999997] * rows
    table = pa.table(
        [md, azi, [None, 29.999999847691296] * (rows // 2) + [1.0]],
        schema=pa.schema([field, angle, tvd]),
    )
    exported = for_export(table)
    assert set(exported.column("md").to_pylist()) == {914.4}
    assert set(exported.column("azi").to_pylist()) == {359.999999}
    tvd_values = exported.column("tvd").to_pylist()
    assert tvd_values[:2] == [None, 30.0] and tvd_values[-1] == 1.0
    assert exported.column("tvd").null_count == rows // 2
