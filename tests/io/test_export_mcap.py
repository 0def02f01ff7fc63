"""MCAP of processed streams: a real run's tables, each on its own topic, read back exactly
(units, north references, schema metadata; not the engine's source lines and path), the file checked with the mcap library's own
reader, batching and log times of a long series, and refusals."""

from __future__ import annotations

import json
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError
from pipeline.io.mcap.arrow import BATCH_ROWS, write_samples
from pipeline.io.mcap.crc import crc32_combine
from pipeline.io.mcap.tables import read_tables, write_tables
from pipeline.registry import Provenance
from pipeline.runner import RunResult
from pipeline.streams import MMAP_THRESHOLD, TableStream
from pipeline.well import WellMetadata, attach


def test_processed_streams_read_back_exactly(exports_run: RunResult):
    tables, well = read_tables(exports_run.out_dir / "processed.mcap")
    assert sorted(tables) == ["qc", "stations", "trajectory"]
    expected = {
        "trajectory": pq.read_table(exports_run.out_dir / "uncertainty.trajectory.parquet"),
        "qc": pq.read_table(exports_run.out_dir / "dls_check.results.parquet"),
        "stations": attach(exports_run.tables[("grid", "stations")], exports_run.well),
    }
    stations = expected["stations"]  # read from a file: its lines and path stay behind
    assert "source_line" in stations.column_names
    meta = {k: v for k, v in stations.schema.metadata.items() if k != b"gyropipe.source"}
    expected["stations"] = stations.drop_columns(["source_line"]).replace_schema_metadata(meta)
    for role, table in expected.items():
        assert tables[role].equals(table, check_metadata=True), role
        assert tables[role].schema.metadata == table.schema.metadata, role
    assert tables["trajectory"].schema.field("azi").metadata == {
        UNIT_KEY: b"deg",
        NORTH_KEY: b"grid",
    }
    assert well == exports_run.well


def test_file_as_the_mcap_library_sees_it(exports_run: RunResult):
    with (exports_run.out_dir / "processed.mcap").open("rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert summary is not None
        channels = {c.topic: c for c in summary.channels.values()}
        assert sorted(channels) == ["/gyropipe/qc", "/gyropipe/stations", "/gyropipe/trajectory"]
        assert {c.message_encoding for c in channels.values()} == {"arrow.ipc.record_batch"}
        assert {summary.schemas[c.schema_id].encoding for c in channels.values()} == {
            "arrow.ipc.schema"
        }
        assert {summary.schemas[c.schema_id].name for c in channels.values()} == {
            "gyropipe.qc",
            "gyropipe.stations",
            "gyropipe.trajectory",
        }
        records = {m.name: m.metadata for m in reader.iter_metadata()}
    manifest = json.loads((exports_run.out_dir / "run.json").read_text())
    assert records["gyropipe.run"]["pipeline_sha256"] == manifest["pipeline"]["sha256"]
    assert records["gyropipe.well"]["well"] == "J-12"
    assert records["gyropipe.well"]["grid_convergence"] == "1.25"
    assert records["gyropipe.units/trajectory"]["dls"] == "deg/30m"
    assert records["gyropipe.units/qc"]["check"] == ""


def _provenance() -> Provenance:
    import datetime as dt

    return Provenance("p", "1", "p.yaml", "0" * 64, "0.1.0", {}, {}, dt.datetime.now(dt.UTC), ())


def test_long_series_is_batched_and_logged_at_its_times(tmp_path: Path):
    n = 2 * BATCH_ROWS + 500
    time = 100.0 + 0.01 * np.arange(n)
    series = pa.Table.from_arrays(
        [pa.array(time), pa.array(np.sin(time)), pa.array(np.arange(n) % 3)],
        schema=pa.schema(
            [
                pa.field("time", pa.float64(), metadata={UNIT_KEY: b"s"}),
                pa.field("azi", pa.float64(), metadata={UNIT_KEY: b"deg", NORTH_KEY: b"true"}),
                pa.field("flags", pa.int64()),
            ]
        ),
    )
    path = tmp_path / "s.mcap"
    write_tables({"series": series}, path, WellMetadata(well="S"), _provenance())
    with path.open("rb") as fh:
        stamps = [m.log_time for _, _, m in make_reader(fh).iter_messages()]
    assert stamps == [round(time[i] * 1e9) for i in (0, BATCH_ROWS, 2 * BATCH_ROWS)]
    tables, well = read_tables(path)
    assert tables["series"].equals(series, check_metadata=True)
    assert well == WellMetadata(well="S")


def test_a_full_rate_series_goes_in_chunks_below_the_mmap_threshold(tmp_path: Path):
    """A series of several MB (six float columns, as the continuous pipeline's) is written in
    chunks of one or two messages, each under the allocator's mmap threshold (their buffers
    are reused from the heap, not mapped afresh), and reads back exactly."""
    n = 6 * BATCH_ROWS + 123
    rng = np.random.default_rng(5)
    columns = {"time": 10.0 + 0.01 * np.arange(n), **{c: rng.normal(size=n) for c in "abcde"}}
    series = pa.table(columns)
    path = tmp_path / "s.mcap"
    write_tables({"series": series}, path, WellMetadata(well="S"), _provenance())
    with path.open("rb") as fh:
        summary = make_reader(fh).get_summary()
    assert summary is not None and summary.statistics.message_count == 7
    chunks = summary.chunk_indexes
    assert len(chunks) >= 4
    assert all(c.uncompressed_size < MMAP_THRESHOLD for c in chunks)
    tables, _ = read_tables(path)
    assert _ipc(tables["series"]) == _ipc(series)


def _data_section(path: Path) -> tuple[bytes, int]:
    """The bytes of the file's data section (its start to the DataEnd record) and the CRC
    its DataEnd record holds, found from the footer (the summary starts after DataEnd)."""
    data = path.read_bytes()
    footer = data[-8 - 29 : -8]
    assert footer[0] == 0x02  # Footer: opcode, length, summary start, …
    summary_start = int.from_bytes(footer[9:17], "little")
    end = summary_start - 13
    assert data[end] == 0x0F and int.from_bytes(data[end + 1 : end + 9], "little") == 4
    return data[:end], int.from_bytes(data[end + 9 : end + 13], "little")


def test_the_data_section_crc_covers_every_byte_of_it(tmp_path: Path):
    """The DataEnd record's CRC is CRC-32 of the whole data section (the chunks' messages
    are CRC'd once, for their chunk, and the data CRC carried over them): tables of several
    chunks, a stream, and a samples file in larger chunks."""
    n = 6 * BATCH_ROWS + 123
    rng = np.random.default_rng(6)
    series = pa.table({"time": 10.0 + 0.01 * np.arange(n), "a": rng.normal(size=n)})
    small = pa.table({"md": [1.0, 2.0], "inc": [0.5, 0.7]})
    tables = tmp_path / "t.mcap"
    stream = TableStream(series.schema, lambda: iter(series.to_batches(max_chunksize=9_000)))
    write_tables(
        {"series": stream, "trajectory": small}, tables, WellMetadata(well="T"), _provenance()
    )
    samples = tmp_path / "s.mcap"
    write_samples(series, samples, WellMetadata(well="S"))
    for path in (tables, samples):
        data, crc = _data_section(path)
        assert crc != 0 and crc == zlib.crc32(data), path.name
    read, _ = read_tables(tables)  # the reader checks every CRC
    assert _ipc(read["series"]) == _ipc(series)


@pytest.mark.parametrize("length", [0, 1, 7, 4096, 524_288 + 49])
def test_crc32_combine_is_zlibs_crc_carried_over(length: int):
    rng = np.random.default_rng(length)
    data = rng.integers(0, 256, length, dtype=np.uint8).tobytes()
    for start in (0, 1, 0xFFFFFFFF, 0x1234ABCD):
        assert crc32_combine(start, zlib.crc32(data), length) == zlib.crc32(data, start)


def _counted_stream(table: pa.Table, passes: list[int]) -> TableStream:
    """``table`` as a stream of batches, counting its passes in ``passes``."""

    def batches() -> Iterator[pa.RecordBatch]:
        passes.append(1)
        yield from table.to_batches(max_chunksize=BATCH_ROWS)

    return TableStream(table.schema, batches)


@pytest.mark.parametrize("gap", [None, "null", "nan"])
def test_a_streamed_series_is_read_once_unless_its_times_cannot_stamp(
    tmp_path: Path, gap: str | None
):
    """A stream is written in one pass, its messages logged at their first rows' times; a
    time column with a null or a NaN in a later batch logs every message of the stream at
    0 (the file written again: a second pass), the other tables at their own times."""
    n = 2 * BATCH_ROWS + 500
    time = pa.array(100.0 + 0.01 * np.arange(n))
    if gap is not None:
        values = time.to_pylist()
        values[BATCH_ROWS + 7] = None if gap == "null" else float("nan")
        time = pa.array(values, pa.float64())
    schema = pa.schema([pa.field("time", pa.float64(), metadata={UNIT_KEY: b"s"})])
    series = pa.Table.from_arrays([time, pa.array(np.arange(n))], names=["time", "n"])
    series = series.cast(schema.append(pa.field("n", pa.int64())))
    stations = pa.table({"time": [5.0, 6.0], "md": [0.0, 10.0]})
    passes: list[int] = []
    path = tmp_path / "s.mcap"
    tables = {"stations": stations, "series": _counted_stream(series, passes)}
    write_tables(tables, path, WellMetadata(well="S"), _provenance())
    with path.open("rb") as fh:
        messages = make_reader(fh).iter_messages(log_time_order=False)
        stamps = [(c.topic, m.log_time) for _, c, m in messages]
    logged = [0, 0, 0] if gap else [100_000_000_000, 200_000_000_000, 300_000_000_000]
    assert stamps == [("/gyropipe/stations", 5_000_000_000)] + [
        ("/gyropipe/series", t) for t in logged
    ]
    assert len(passes) == (2 if gap else 1)
    back, _ = read_tables(path)
    assert _ipc(back["series"]) == _ipc(series)  # bit for bit, NaN included


def _ipc(table: pa.Table) -> bytes:
    """The table, its chunks combined, as Arrow IPC stream bytes (schema metadata too)."""
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write_table(table.combine_chunks())
    return sink.getvalue().to_pybytes()


def test_refusals_and_typed_errors(tmp_path: Path):
    path = tmp_path / "x.mcap"
    coded = pa.table({"check": pa.array(["a", "b"]).dictionary_encode()})
    with pytest.raises(ValueError, match="dictionary-encoded"):
        write_tables({"qc": coded}, path, WellMetadata(), _provenance())
    samples = pa.Table.from_arrays(
        [pa.array([0.0, 1.0])], schema=pa.schema([pa.field("time", pa.float64())])
    )
    write_samples(samples, path, WellMetadata())
    with pytest.raises(InputFileError, match="no processed-table channel"):
        read_tables(path)
    write_tables({"qc": pa.table({"check": ["a"] * 50})}, path, WellMetadata(), _provenance())
    data = bytearray(path.read_bytes())
    data[len(data) // 3] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(InputFileError) as caught:
        read_tables(path)
    assert caught.value.path == str(path)
