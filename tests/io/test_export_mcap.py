"""MCAP of processed streams: a real run's tables, each on its own topic, read back exactly
(units, north references, schema metadata), the file checked with the mcap library's own
reader, batching and log times of a long series, and refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError
from pipeline.io.mcap.arrow import BATCH_ROWS, write_samples
from pipeline.io.mcap.tables import read_tables, write_tables
from pipeline.registry import Provenance
from pipeline.runner import RunResult
from pipeline.well import WellMetadata, attach


def test_processed_streams_read_back_exactly(exports_run: RunResult):
    tables, well = read_tables(exports_run.out_dir / "processed.mcap")
    assert sorted(tables) == ["qc", "stations", "trajectory"]
    expected = {
        "trajectory": pq.read_table(exports_run.out_dir / "uncertainty.trajectory.parquet"),
        "qc": pq.read_table(exports_run.out_dir / "dls_check.results.parquet"),
        "stations": attach(exports_run.tables[("grid", "stations")], exports_run.well),
    }
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
