"""``io.nulls.value_range`` (the extremes the CSV reader's finiteness test and null-marker
search start from) against Python's own min/max, ``null_markers`` on columns whose
extremes alone cannot clear them (a NaN, a marker, nulls), and a non-finite cell far into a
block of CSV rows (a later chunk of its columns) refused at its line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

from pipeline.errors import InputFileError
from pipeline.io import threads as io_threads
from pipeline.io.csv import read
from pipeline.io.nulls import marked_rows, null_markers, value_range


def test_value_range_is_the_min_and_max_over_every_chunk() -> None:
    values = pa.chunked_array([[3.0, -1.5], [], [7.25, 0.0]])
    assert value_range(values) == (-1.5, 7.25)
    assert value_range(pa.array([2.0])) == (2.0, 2.0)


def test_value_range_carries_a_nan_and_an_infinity() -> None:
    low, high = value_range(pa.chunked_array([[1.0], [math.nan, 2.0]]))  # type: ignore[misc]
    assert math.isnan(low) and math.isnan(high)
    assert value_range(pa.array([1.0, -math.inf])) == (-math.inf, 1.0)


def test_value_range_declines_nulls_other_types_and_no_values() -> None:
    assert value_range(pa.array([1.0, None])) is None
    assert value_range(pa.array([1, 2], pa.int64())) is None
    assert value_range(pa.array([1.0], pa.float32())) is None
    assert value_range(pa.chunked_array([], pa.float64())) is None


def test_null_markers_are_found_beside_a_nan_and_among_nulls() -> None:
    found = null_markers(pa.array([1.0, math.nan, -999.25]), angle=False)
    assert found is not None and found.tolist() == [False, False, True]
    found = null_markers(pa.array([None, -9999.25, 2.0]), angle=False)
    assert found is not None and found.tolist() == [False, True, False]
    assert null_markers(pa.array([1.0, math.nan, 999.25]), angle=False) is None
    angles = null_markers(pa.chunked_array([[10.0], [999.25]]), angle=True)
    assert angles is not None and np.flatnonzero(angles).tolist() == [1]


def test_marked_rows_tells_each_column_of_a_stack_by_its_own_markers() -> None:
    nan = math.nan
    stacked = np.array(
        [
            [1.0, nan, -999.25],  # a marker of every column beside a NaN
            [1.0, nan, 999.25],  # + 999.25: a marker of an angle only
            [10.0, nan, 999.25],  # the same, an angle
            [nan, nan, nan],  # no values at all
            [-2000.0, 5000.0, 3.0],  # beyond ±999.25 but no marker
            [-9999.25, 0.0, 1.0],
        ]
    )
    angle = np.array([False, False, True, True, True, False])
    assert marked_rows(stacked, angle).tolist() == [True, False, True, False, False, True]
    assert marked_rows(np.empty((2, 0)), np.array([True, False])).tolist() == [False, False]


@pytest.mark.parametrize("threads", [1, 2], ids=["one thread", "two threads"])
@pytest.mark.parametrize("cell", ["nan", "inf", "-Infinity"])
def test_a_non_finite_cell_in_a_later_chunk_of_a_block_is_refused_at_its_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, threads: int, cell: str
) -> None:
    """``pyarrow.csv`` parses a block of rows in chunks of 1 MiB (512 KiB on threads): a
    non-finite cell in the last chunk of a 3 MB block is refused as in the first."""
    monkeypatch.setattr(io_threads, "reader_threads", lambda: threads)
    header = ",".join(
        ["time [s]", *(f"gyro_{a} [deg/h]" for a in "xyz"), *(f"acc_{a} [m/s2]" for a in "xyz")]
    )
    rows = [f"{i / 100:.2f},{i * 1e-3:.6f},-0.5,2,0.1,-0.2,9.8" for i in range(80_000)]
    rows[79_000] = rows[79_000].rsplit(",", 1)[0] + f",{cell}"
    path = tmp_path / "samples.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    assert path.stat().st_size > 2 << 20
    with pytest.raises(InputFileError) as info:
        read(path, "samples", None)
    assert info.value.line == 79_002
