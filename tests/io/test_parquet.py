"""The Parquet reader on broken files (fuzz findings): one-line located errors, never a
reader crash."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pipeline.errors import InputFileError, InputFileWarning
from pipeline.io import parquet as parquet_plugin
from pipeline.plugins import load_registry
from pipeline.streams import BATCH_ROWS, TableStream
from pipeline.tables import Stations
from pipeline.well import WELL_KEY, WellMetadata, attach
from tests_support import ROOT, gyropipe_cli, plugin_io

READER, WRITER = plugin_io(parquet_plugin)


def stations(tmp_path: Path, well: bytes | None = None) -> Path:
    table = Stations.compiled().make_table(
        {"md": [0.0, 30.0], "inc": [0.0, 1.0], "azi": [0.0, 10.0]}, north_reference="true"
    )
    table = attach(table, WellMetadata(well="P-1"))
    if well is not None:
        table = table.replace_schema_metadata({**table.schema.metadata, WELL_KEY: well})
    path = tmp_path / "st.parquet"
    pq.write_table(table, path)
    return path


@pytest.mark.parametrize(
    ("stored", "reason"),
    [
        (b'{"latitude": NaN}', "latitude: Input should be a finite number"),
        (b"[]", "value: Input should be a valid dictionary"),
        (b'{"bogus": 1}', "bogus: Extra inputs are not permitted"),
        (b"{", "not JSON text: Expecting property name"),
        (b"\x9d\x87.\xbe", "not JSON text: 'utf-8' codec can't decode byte 0x9d"),
    ],
)
def test_unreadable_well_metadata_is_the_files_fault(tmp_path: Path, stored: bytes, reason: str):
    """These were a ReaderError wrapping a pydantic ValidationError, a JSONDecodeError or a
    UnicodeDecodeError, naming neither the file nor the metadata."""
    path = stations(tmp_path, stored)
    with pytest.raises(InputFileError) as caught:
        load_registry().read(path, "stations")
    text = str(caught.value)
    assert text.startswith(
        f"{path}: well metadata ('gyropipe.well' in the schema metadata): {reason}"
    ), text
    assert "\n" not in text


def test_a_readable_file_keeps_its_well(tmp_path: Path):
    table, well = load_registry().read(stations(tmp_path), "stations")
    # the azimuths' north is the well's
    assert well == WellMetadata(well="P-1", north_reference="true") and table.num_rows == 2


def test_an_unreadable_file_is_one_line(tmp_path: Path):
    """pyarrow's message ends in a newline: the error was printed over two lines."""
    data = bytearray(stations(tmp_path).read_bytes())
    data[-12:-8] = b"\xff\xff\xff\x7f"  # the footer's metadata length
    path = tmp_path / "broken.parquet"
    path.write_bytes(bytes(data))
    with pytest.raises(InputFileError, match="not a readable Parquet file") as caught:
        READER.read(path, "stations", None)
    assert "\n" not in str(caught.value) and str(caught.value).startswith(f"{path}: ")


def test_writer_round_trip(tmp_path: Path):
    table = pa.table({"md": pa.array([1.0])})
    WRITER.write(table, tmp_path / "t.parquet", WellMetadata())
    assert pq.read_table(tmp_path / "t.parquet").equals(table)


def test_the_buffered_writes_are_pyarrows_own_bytes(tmp_path: Path):
    """Through its write buffer a table, and a stream of several row groups (more bytes than
    the buffer holds), are written byte for byte as pyarrow writes them to a path."""
    rng = np.random.default_rng(1)
    n = 200_000  # 3.2 MB of floats: past WRITE_BUFFER, the buffer flushed mid-file
    table = pa.table({"t": rng.random(n), "k": pa.array(np.arange(n) % 7)})
    assert table.nbytes > parquet_plugin.WRITE_BUFFER
    plain = dict(use_dictionary=["k"])
    WRITER.write(table, tmp_path / "w.parquet", WellMetadata())
    pq.write_table(table, tmp_path / "p.parquet", row_group_size=BATCH_ROWS, **plain)
    assert (tmp_path / "w.parquet").read_bytes() == (tmp_path / "p.parquet").read_bytes()
    stream = TableStream.from_table(table)
    WRITER.write_stream(stream, tmp_path / "ws.parquet", WellMetadata())
    with pq.ParquetWriter(tmp_path / "ps.parquet", table.schema, **plain) as writer:
        for batch in stream:
            writer.write_batch(batch)
    assert (tmp_path / "ws.parquet").read_bytes() == (tmp_path / "ps.parquet").read_bytes()
    assert pq.ParquetFile(tmp_path / "ws.parquet").num_row_groups == 4
    assert pq.read_table(tmp_path / "ws.parquet").equals(table)


def test_a_column_name_that_is_not_text_is_located(tmp_path: Path):
    """Fuzz finding: a flipped byte in a column name of the footer read, then failed with a
    UnicodeDecodeError when the names were asked for (a ReaderError naming no file)."""
    path = tmp_path / "names.parquet"
    pq.write_table(pa.table({"md": [0.0, 1.0], "zzq": [1.0, 2.0]}), path)
    data = path.read_bytes()
    assert data.count(b"zzq") == 2  # the Parquet schema and the footer's column chunk
    path.write_bytes(data.replace(b"zzq", b"\xe8zq"))
    with pytest.raises(InputFileError) as caught:
        load_registry().read(path, "stations")
    assert str(caught.value) == (
        f"{path}: column 2: its name is not UTF-8 text (invalid continuation byte)"
    )


@pytest.mark.parametrize(
    ("metadata", "problem"),
    [
        (
            {b"unit": b"de\xb0", b"north_reference": b"true"},
            "unit: expected unit 'deg' in field metadata, got 'de\ufffd'",
        ),
        (
            {b"unit": b"deg", b"north_reference": b"tr\xffe"},
            "north reference: expected one of true, grid, magnetic",
        ),
    ],
    ids=["unit", "north-reference"],
)
def test_field_metadata_that_is_not_text_is_a_contract_violation(
    tmp_path: Path, metadata: dict[bytes, bytes], problem: str
):
    """Fuzz finding: the contract check decoded a column's unit or north reference and
    ended in a UnicodeDecodeError (a traceback out of ``gyropipe convert``)."""
    path = stations(tmp_path)
    table = pq.read_table(path)
    i = table.schema.get_field_index("azi")
    table = table.set_column(i, table.schema.field(i).with_metadata(metadata), table.column(i))
    pq.write_table(table, path)
    with pytest.raises(InputFileError) as caught:
        load_registry().read(path, "stations")
    assert str(caught.value) == (
        f"{path}: not valid as stations (reader 'parquet'): column 'azi': {problem}"
    )


@pytest.mark.parametrize("whole", [True, False], ids=["read-whole", "buffered"])
def test_a_stream_gives_the_files_rows_read_whole_or_through_a_buffer(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, whole: bool
):
    """Row groups of at most READ_WHOLE bytes are read whole, larger ones through the
    buffer: either way the stream's batches are the file's rows, its schema and well."""
    table = Stations.compiled().make_table(
        {"md": [30.0 * i for i in range(5000)], "inc": [0.5] * 5000, "azi": [10.0] * 5000},
        north_reference="true",
    )
    table = attach(table, WellMetadata(well="P-1"))
    path = tmp_path / "rows.parquet"
    pq.write_table(table, path, row_group_size=1200)
    if not whole:
        monkeypatch.setattr(parquet_plugin, "READ_WHOLE", 1000)  # < a row group's bytes
    stream, well = READER.stream(path, "stations", None)
    read = pa.Table.from_batches(list(stream), schema=stream.schema)
    assert read.equals(table, check_metadata=True)
    assert well == WellMetadata(well="P-1", north_reference="true")


def test_the_north_the_azimuth_column_names_is_the_wells(tmp_path: Path) -> None:
    # azimuths naming grid beside well metadata naming none (or true) read as a well of
    # survey.yaml's true north: run.json and trajectory.csv stated true beside grid azimuths
    table = Stations.compiled().make_table(
        {"md": [0.0, 30.0], "inc": [0.0, 1.0], "azi": [0.0, 10.0]}, north_reference="grid"
    )
    path = tmp_path / "grid.parquet"
    pq.write_table(attach(table, WellMetadata(well="P-1")), path)
    assert READER.read(path, "stations", None)[1].north_reference == "grid"
    out = tmp_path / "out"
    survey = ROOT / "pipelines" / "survey.yaml"
    result = gyropipe_cli(
        "run", survey, "--input", path, "--out", out, "--set", "report.formats=[html]"
    )
    assert result.returncode == 0, result.stderr
    assert json.loads((out / "run.json").read_text())["well"]["north_reference"] == "grid"
    assert "# well.north_reference=grid\n" in (out / "trajectory.csv").read_text()
    pq.write_table(attach(table, WellMetadata(well="P-1", north_reference="true")), path)
    with pytest.warns(InputFileWarning, match="well.north_reference 'true' contradicts"):
        assert READER.read(path, "stations", None)[1].north_reference == "grid"
