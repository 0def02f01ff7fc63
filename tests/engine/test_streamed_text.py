"""The CSV and LAS readers of raw samples stream (issue #20): a block of rows at a time,
checked as it passes, equal to the read of the file in one block, every row at its own
file line across blocks, errors located in any block, the reader's own memory bounded by a
few blocks, and a pipeline reading either holds few batches alive."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pipeline.errors import InputFileError
from pipeline.gyrocompass.readings import position_readings
from pipeline.io import threads as io_threads
from pipeline.io.csv import rows as csv_rows
from pipeline.io.las import fast as las_fast
from pipeline.plugins import load_registry
from pipeline.registry import ReaderDef
from pipeline.streams import TableStream
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata
from stream_support import PIPELINE, Alive, registry_with, run, survey

SMALL = 8 * 1024
"""Bytes per block in these tests: a file of 15,000 rows (~1.7 MB) is hundreds of blocks."""
ROWS = 15_000
FORMATS = ["csv", "las"]
_DATA_LINE = re.compile(r"^\s*-?[0-9]")


@pytest.fixture
def small_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(csv_rows, "ROWS_BLOCK", SMALL)
    monkeypatch.setattr(las_fast, "BLOCK", SMALL)


def samples(rows: int | None) -> pa.Table:
    """The simulated survey (its first ``rows``) without its frame angle (written rounded,
    359.99999… becomes 360, which the contract refuses)."""
    table = survey().drop_columns(["frame_angle"])
    return table if rows is None else table.slice(0, rows)


def write(tmp_path: Path, fmt: str, *, notes: bool = False, rows: int | None = ROWS) -> Path:
    """The samples written by the built-in writer of ``fmt``; ``notes`` adds comment
    lines (and, in CSV, blank lines) among the data rows."""
    path = tmp_path / f"samples.{fmt}"
    load_registry().writers[fmt][0].write(samples(rows), path, WellMetadata(well="S-1"))
    if notes:
        lines = path.read_text().split("\n")
        first = next(i for i, line in enumerate(lines) if _DATA_LINE.match(line))
        for at in range(len(lines) - 5, first, -(997 if fmt == "csv" else 4001)):
            lines.insert(at, "# note")
            if fmt == "csv" and at % 2:
                lines.insert(at, "")
        path.write_text("\n".join(lines))
    return path


def data_lines(path: Path) -> tuple[list[int], list[float]]:
    """The file line and first value (time, s) of every data row, read from the text."""
    numbered = enumerate(path.read_text().split("\n"), start=1)
    rows = [(n, line) for n, line in numbered if _DATA_LINE.match(line)]
    return [n for n, _ in rows], [float(re.split(r"[,\s]+", line.strip())[0]) for _, line in rows]


def read_whole(path: Path, monkeypatch: pytest.MonkeyPatch) -> pa.Table:
    """The file read in one block."""
    with monkeypatch.context() as patch:
        patch.setattr(csv_rows, "ROWS_BLOCK", 1 << 30)
        patch.setattr(las_fast, "BLOCK", 1 << 30)
        return load_registry().read(path, "samples")[0]


@pytest.mark.parametrize("notes", [False, True], ids=["plain", "with comment lines"])
@pytest.mark.parametrize("fmt", FORMATS)
def test_a_streamed_read_equals_the_read_in_one_block(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, small_blocks: None, fmt: str, notes: bool
) -> None:
    path = write(tmp_path, fmt, notes=notes)
    stream, well = load_registry().read_stream(path, "samples")
    assert well.well == "S-1"
    batches = list(stream)
    assert len(batches) > 100
    streamed = pa.Table.from_batches(batches, schema=stream.schema)
    whole = read_whole(path, monkeypatch)
    assert streamed.equals(whole)
    assert stream.schema.equals(whole.schema, check_metadata=True)
    lines, times = data_lines(path)
    assert streamed.column("source_line").to_pylist() == lines
    assert streamed.column("time").to_pylist() == times
    assert load_registry().read(path, "samples")[0].equals(whole)  # the reader's own blocks


@pytest.mark.parametrize(
    ("fmt", "threads"), [("csv", 1), ("csv", 3), ("las", 1)], ids=["csv", "csv-threads", "las"]
)
def test_a_bad_cell_in_a_late_block_is_located_on_its_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, small_blocks: None, fmt: str, threads: int
) -> None:
    """Also when the CSV reader parses blocks on three threads ahead of the one handed on
    (a reader alone on three cores or more): the bad cell's line is counted from the
    blocks before."""
    monkeypatch.setattr(io_threads, "reader_threads", lambda: threads)
    path = write(tmp_path, fmt, notes=True)
    lines, _ = data_lines(path)
    bad = lines[len(lines) * 3 // 4]
    text = path.read_text().split("\n")
    text[bad - 1] = text[bad - 1].replace("9.", "9.x", 1)
    assert "9.x" in text[bad - 1]
    path.write_text("\n".join(text))
    stream, _ = load_registry().read_stream(path, "samples")
    batches = iter(stream)
    passed = 0
    while passed < 50:  # the blocks before it are handed on first
        next(batches)
        passed += 1
    with pytest.raises(InputFileError) as info:
        list(batches)
    assert info.value.line == bad
    with pytest.raises(InputFileError) as whole:
        load_registry().read(path, "samples")
    assert str(whole.value) == str(info.value)


STEPPED = """~Version
 VERS. 2.0 : v
 WRAP. NO : w
~Well
 STRT.S 0.0 : start
 STOP.S {stop} : stop
 STEP.S 0.5 : step
 NULL. -999.25 : null
~Curve
 TIME.S : time
 WX.DEG/HR : gyro x
 WY.DEG/HR : gyro y
 WZ.DEG/HR : gyro z
 GX.M/S2 : acc x
 GY.M/S2 : acc y
 GZ.M/S2 : acc z
~A
"""


@pytest.mark.parametrize("lost", range(100, 106))
def test_a_lost_las_row_at_any_block_border_is_located(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, lost: int
) -> None:
    """STEP is checked across block borders: a row missing just before, at or after one
    is reported on the line after the gap, as the whole read reports it."""
    rows = [
        f"{0.5 * i:8.1f}{1.0:10.4f}{2.0:10.4f}{3.0:10.4f}{0.0:9.4f}{0.0:9.4f}{9.8:9.4f}"
        for i in range(400)
    ]
    monkeypatch.setattr(las_fast, "BLOCK", 4 * (len(rows[0]) + 1))  # about 5 rows a block
    kept = rows[:lost] + rows[lost + 1 :]
    path = tmp_path / "lost.las"
    path.write_text(STEPPED.format(stop=0.5 * 399) + "\n".join(kept) + "\n")
    title = STEPPED.count("\n")
    stream, _ = load_registry().read_stream(path, "samples")
    with pytest.raises(InputFileError, match=r"STEP is 0\.5 but the index steps by 1 ") as info:
        list(stream)
    assert info.value.line == title + lost + 1


@pytest.mark.parametrize(("threads", "share"), [(False, 20), (True, 5)])
def test_the_reader_holds_a_few_blocks_not_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, small_blocks: None, threads: bool, share: int
) -> None:
    """While a stream of either reader is consumed batch by batch, Arrow's memory in use
    stays a small part of the table the whole read holds: 1/20 on one thread; 1/5 with blocks
    read ahead on threads (a reader alone), as each parse in progress also holds pyarrow's
    working buffers (~130 KiB whatever the block's size)."""
    monkeypatch.setattr(io_threads, "reader_threads", lambda: 2 if threads else 1)
    for fmt in FORMATS:
        path = write(tmp_path, fmt)
        whole = load_registry().read(path, "samples")[0]
        stream, _ = load_registry().read_stream(path, "samples")
        base, peak, rows = pa.total_allocated_bytes(), 0, 0
        for batch in stream:
            peak = max(peak, pa.total_allocated_bytes() - base)
            rows += batch.num_rows
            del batch
        assert rows == whole.num_rows
        assert peak < whole.nbytes / share, (fmt, peak, whole.nbytes)


def test_csv_blocks_parsed_on_threads_hold_a_few_blocks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With blocks parsed on three threads, a few ahead of the one handed on, Arrow's memory
    in use while the long survey streams stays a small part of the whole read's table:
    blocks of 64 KiB, as each parse in progress holds pyarrow's working buffers (~130 KiB
    whatever the block's size)."""
    monkeypatch.setattr(csv_rows, "ROWS_BLOCK", 64 * 1024)
    monkeypatch.setattr(io_threads, "reader_threads", lambda: 3)
    path = write(tmp_path, "csv", rows=None)
    whole = load_registry().read(path, "samples")[0]
    stream, _ = load_registry().read_stream(path, "samples")
    base, peak, batches = pa.total_allocated_bytes(), 0, []
    for batch in stream:
        peak = max(peak, pa.total_allocated_bytes() - base)
        batches.append(batch.num_rows)
        del batch
    assert sum(batches) == whole.num_rows and len(batches) > 50
    assert peak < whole.nbytes / 10, (peak, whole.nbytes)


def tracked(fmt: str, alive: Alive) -> ReaderDef:
    """The built-in ``fmt`` reader, each batch of its stream remade from tracked arrays."""
    builtin = load_registry().readers[fmt][0]
    assert builtin.stream is not None
    opener = builtin.stream

    def stream(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
        inner, well = opener(path, kind, options)

        def batches() -> Iterator[pa.RecordBatch]:
            for batch in inner:
                yield alive.track(batch)

        return TableStream(inner.schema, batches), well

    return ReaderDef(
        name="counting",
        description=f"{fmt}, batches counted",
        kinds={"samples": RawSamples},
        read=builtin.read,
        sniff=lambda path: False,
        options=builtin.options,
        stream=stream,
    )


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_pipeline_reading_csv_or_las_holds_few_batches_alive(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fmt: str
) -> None:
    """Blocks of about 1000 rows (as the Parquet test's batches): a position's samples
    span at most two of them."""
    monkeypatch.setattr(csv_rows, "ROWS_BLOCK", 112 * 1024)
    monkeypatch.setattr(las_fast, "BLOCK", 112 * 1024)
    path = write(tmp_path, fmt, rows=None)
    whole = load_registry().read(path, "samples")[0]
    alive = Alive()
    run(tmp_path, registry_with(tracked(fmt, alive)), PIPELINE, path)
    assert alive.made > 100
    assert alive.peak <= 3, f"{alive.peak} of {alive.made} batches alive at once"
    out = tmp_path / "out"
    readings = pq.read_table(out / "readings.readings.parquet")
    expected = position_readings(whole.drop_columns(["source_line"]))
    assert readings.select(expected.column_names).equals(expected)
    copied = pq.read_table(out / "copy.parquet")
    assert np.array_equal(copied.column("time").to_numpy(), whole.column("time").to_numpy())
    assert alive.now == 0
