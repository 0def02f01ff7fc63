"""No silent non-finite value (issue 32 item 12): a log's index that is not a finite,
strictly monotonic number is an error naming its line (text formats) or row (Parquet), in
the ``log`` kind as in every other; a curve cell spelling an infinite number is one too;
the CSV writer writes ±inf as it writes NaN, an empty cell."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import InputFileError
from pipeline.io.csv import write_csv
from pipeline.plugin import ContractViolation, LogTable
from pipeline.well import WellMetadata
from tests_support import ROOT, gyropipe_cli

GR = ROOT / "tests" / "data" / "las" / "gr.las"
ROW_1501 = " 1501.0    52.90"
"""Line 26 of gr.las, the third row."""


def _las(tmp_path: Path, depth: str = " 1501.0", gr: str = "    52.90") -> Path:
    path = tmp_path / "log.las"
    path.write_text(GR.read_text().replace(ROW_1501, f"{depth}{gr}"))
    return path


@pytest.mark.parametrize("depth", ["-inf", "Infinity", "abc", "nan", "1500.0", "1499.0"])
def test_a_las_depth_that_is_no_finite_increasing_number_is_refused_at_its_line(
    tmp_path: Path, depth: str
) -> None:
    """Before: the depth became a text column (or kept NaN, a repeated or backward depth)
    and the copy was re-indexed on GR, ``-inf`` written literally, exit 0."""
    src = _las(tmp_path, f" {depth}")
    out = tmp_path / "copy.las"
    result = gyropipe_cli("convert", src, out)
    assert result.returncode == 1
    assert not out.exists()
    (line,) = [e for e in result.stderr.splitlines() if e.startswith("error:")]  # STEP: warned
    assert line.startswith(f"error: {src}:26")
    assert ("out of range" in line) or ("index: expected finite, strictly monotonic" in line)


def test_a_las_curve_cell_spelling_infinity_is_refused_not_read_as_text(tmp_path: Path) -> None:
    src = _las(tmp_path, gr="    -inf")
    with pytest.raises(InputFileError, match=r"'-inf' is out of range") as caught:
        gp.read(src, kind="log")
    assert caught.value.line == 26


def test_a_log_recorded_upwards_still_reads() -> None:
    """A decreasing index is a log's own order (STEP < 0): lasio's sample."""
    table = gp.read(ROOT / "tests/data/las/lasio/1.2/sample.las", kind="log")
    depths = table["DEPT"].tolist()
    assert depths == [1670.0, 1669.875, 1669.75]


@pytest.mark.parametrize(
    ("md", "gr", "where"),
    [
        ([0.0, 10.0, math.inf], [1.0, 2.0, 3.0], "column 'md': index"),
        ([0.0, -math.inf, 20.0], [1.0, 2.0, 3.0], "column 'md': index"),
        ([0.0, 10.0, 20.0], [1.0, -math.inf, 3.0], "column 'gr': finite"),
        ([0.0, 20.0, 10.0], [1.0, 2.0, 3.0], "column 'md': index"),
    ],
)
def test_a_parquet_log_with_infinite_values_is_refused_naming_column_and_row(
    tmp_path: Path, md: list[float], gr: list[float], where: str
) -> None:
    """Before: ``--kind log`` passed ±inf through to the copy."""
    src = tmp_path / "log.parquet"
    pq.write_table(pa.table({"md": md, "gr": gr}), src)
    result = gyropipe_cli("convert", "--kind", "log", src, tmp_path / "copy.csv")
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"error: {src}: not valid as log")
    assert where in line and "first: row " in line


def test_the_csv_writer_writes_infinite_values_as_empty_cells(tmp_path: Path) -> None:
    path = tmp_path / "w.csv"
    write_csv(pa.table({"a": [1.0, math.inf, -math.inf, math.nan]}), path, WellMetadata())
    assert path.read_text().splitlines()[-5:] == ["a", "1", "", "", ""]


def test_the_las_writer_refuses_a_log_indexed_by_text(tmp_path: Path) -> None:
    """Fuzz finding: a log whose first column was text was written indexed on the next
    curve (repeating values), a copy no reader takes back; gp.write says so typed."""
    path = tmp_path / "log.las"
    table = pa.table({"DEPT": ["a", "b", "c"], "GR": [1.0, 1.0, 3.0]})
    with pytest.raises(gp.GyropipeError, match=r"the first column 'DEPT' is text"):
        gp.write(table, path)
    assert not path.exists()


def _null_over_infinity() -> pa.Array:
    """[1.0, null, 3.0] whose null's slot holds the bits of +inf (a writer may leave any)."""
    validity = pa.py_buffer(np.packbits([1, 0, 1], bitorder="little").tobytes())
    values = pa.py_buffer(np.array([1.0, math.inf, 3.0]).tobytes())
    return pa.Array.from_buffers(pa.float64(), 3, [validity, values])


def test_a_log_curve_is_checked_chunk_by_chunk_its_nulls_not_read_as_values() -> None:
    """The curve's chunks are checked in place where they hold no null: an infinite value in
    a later chunk is refused at its row of the whole table, a null whose slot holds inf bits
    is a null."""
    md = pa.chunked_array([[0.0, 1.0, 2.0], [3.0, 4.0]])
    curve = pa.chunked_array([_null_over_infinity(), pa.array([4.0, 5.0])])
    LogTable.validate_table(pa.table({"md": md, "gr": curve}))
    curve = pa.chunked_array([_null_over_infinity(), pa.array([4.0, -math.inf])])
    with pytest.raises(ContractViolation, match=r"column 'gr': finite: .*first: row 4: -inf"):
        LogTable.validate_table(pa.table({"md": md, "gr": curve}))
