"""Hostile inputs (issue 32 items 6, 9, 10, 11, 16): a file cut short while it is in use, chunks
that claim or hold more than they may, JSON metadata nested without end, XML of huge tokens:
each read fast or a located error, never a signal, a MemoryError or a RecursionError. The
files come from ``hostile_inputs`` (shared with the fuzz suite)."""

from __future__ import annotations

import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

from hostile_inputs import (
    csv_wide,
    las_wide,
    mcap_channel_metadata,
    mcap_chunk,
    nested_json,
    parquet_long,
    parquet_wide,
    parquet_with_metadata,
    witsml_attribute,
    witsml_text,
)
from pipeline.errors import InputFileError
from pipeline.io import parquet
from pipeline.io.limits import MAX_COLUMNS, TEXT_MAX
from pipeline.io.mcap import read_samples, write_samples
from pipeline.io.mcap.options import McapOptions
from pipeline.io.mcap.records import MIN_DECOMPRESSED
from pipeline.io.parquet import MIN_DECODED
from pipeline.jsontext import MAX_DEPTH
from pipeline.plugins import load_registry
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli


def refused_by_convert(path: Path, kind: str, suffix: str) -> str:
    """The stderr of ``gyropipe convert PATH OUT --kind KIND``, which must exit 1."""
    out = path.with_name("out" + suffix)
    result = gyropipe_cli("convert", str(path), str(out), "--kind", kind)
    assert result.returncode == 1, result.stderr
    assert not out.exists()
    return result.stderr


JSON = McapOptions(columns={"time": "t"}, units={"time": "s"})
TOO_DEEP = f"JSON nested deeper than {MAX_DEPTH} levels: refused"


# ------------------------------------------------------------- item 6: cut short in use

TRUNCATE_IN_USE = """
import os, sys
from pathlib import Path
from pipeline.io.mcap import stream_samples
from pipeline.io.mcap.options import McapOptions

path = Path(sys.argv[1])
stream, _ = stream_samples(path, "samples", McapOptions())
os.truncate(path, 64)  # cut short while the stream's batches are still to be used
total = sum(batch.num_rows for batch in stream)
values = sum(float(b.column(1).to_numpy().sum()) for b in stream)
print("rows", total, "sum", values)
"""


@pytest.mark.process("a file mapped and cut short kills its process with SIGBUS")
def test_an_mcap_cut_short_while_it_is_read_is_no_signal(tmp_path: Path):
    """Issue 32 item 6: the reader mapped the file and handed out zero-copy views of it;
    truncating the file while ``run`` used them killed the process (exit 135, SIGBUS)."""
    samples = pa.table({"time": np.arange(50_000.0), "gyro_x": np.ones(50_000)})
    path = tmp_path / "s.mcap"
    write_samples(samples, path, WellMetadata())
    script = tmp_path / "read.py"
    script.write_text(TRUNCATE_IN_USE)
    done = subprocess.run(
        [sys.executable, str(script), str(path)], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, (done.returncode, done.stderr)
    assert done.stdout == "rows 50000 sum 50000.0\n"


# --------------------------------------------------- item 9: decompressed sizes bounded


def test_a_zstd_chunk_claiming_gigabytes_is_refused_before_it_is_decompressed(tmp_path: Path):
    """Issue 32 item 9: a 197 kB MCAP whose zstd chunk claimed 6 GiB reached 6.4 GB RSS and
    ran past 120 s of CPU. Its declared size is checked against the file's budget first."""
    path = tmp_path / "bomb.mcap"
    path.write_bytes(mcap_chunk(declared=6 << 30, actual=64 << 20))
    start = time.process_time()
    stderr = refused_by_convert(path, "samples", ".csv")
    assert time.process_time() - start < 3.0
    assert (
        f"{path}: chunk at byte 32: declares 6,442,450,944 bytes of records; the compressed "
        f"chunks would hold 6,442,450,944 bytes, more than {MIN_DECOMPRESSED:,} (100 times "
        f"the file's {path.stat().st_size:,} bytes, at least {MIN_DECOMPRESSED:,}): refused"
    ) in stderr


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_a_chunk_holding_more_than_it_declares_is_cut_at_the_declared_size(
    tmp_path: Path, compression: str
):
    """A chunk that declares 1,000 bytes and inflates to 8 MiB: decompressed into 1,001
    bytes at most, then refused (the lz4 reader decompressed everything first)."""
    path = tmp_path / "more.mcap"
    path.write_bytes(mcap_chunk(declared=1000, actual=8 << 20, compression=compression))
    with pytest.raises(InputFileError) as info:
        read_samples(path, "samples", JSON)
    assert str(info.value) == (
        f"{path}: chunk at byte 32: decompressed to more than 1000 bytes, header says 1000"
    )


# ------------------------------------------------------ item 10: JSON metadata nesting


@pytest.mark.parametrize("depth", [MAX_DEPTH + 1, 100_000])
def test_deeply_nested_channel_metadata_is_located(tmp_path: Path, depth: int):
    """Issue 32 item 10: channel metadata ``units`` nested 100,000 deep was a
    RecursionError ("reader failed"); nested past the limit it is refused, by name."""
    path = tmp_path / "deep.mcap"
    path.write_bytes(mcap_channel_metadata("units", nested_json(depth)))
    with pytest.raises(InputFileError) as info:
        read_samples(path, "samples", JSON)
    assert str(info.value) == (
        f"{path}: topic '/imu': channel metadata 'units' must be a JSON object key → unit: "
        f"{TOO_DEEP}"
    )


def test_a_parquet_file_of_too_many_columns_is_refused_from_its_footer(tmp_path: Path):
    """Issue 32 item 9: a 35 MB Parquet file of 5,003 columns peaked at 3.6 GB RSS."""
    path = tmp_path / "wide.parquet"
    path.write_bytes(parquet_wide(MAX_COLUMNS - 2))
    stderr = refused_by_convert(path, "stations", ".csv")
    assert f"{path}: footer: 1,001 columns, more than 1,000: refused" in stderr


@pytest.mark.parametrize("streamed", [False, True], ids=["read", "stream"])
def test_a_tiny_run_length_encoded_parquet_file_is_refused_before_decoding(
    tmp_path: Path, streamed: bool
):
    """Issue 32 item 9: RLE packs millions of equal values into a few bytes; a 1.2 MB file
    of 10⁸ rows decoded to 7 GB RSS in 59 s. The footer's row count is checked first."""
    path = tmp_path / "long.parquet"
    path.write_bytes(parquet_long(3_000_000))
    size = path.stat().st_size
    with pytest.raises(InputFileError) as info:
        (parquet.stream if streamed else parquet.read)(path, "stations", None)
    assert str(info.value) == (
        f"{path}: footer: 3,000,000 rows × 3 columns would decode to about 72,000,000 bytes, more "
        f"than {MIN_DECODED:,} (100 times the file's {size:,} bytes, at least "
        f"{MIN_DECODED:,}): refused"
    )


def test_deeply_nested_parquet_well_metadata_is_located(tmp_path: Path):
    """Issue 32 item 10: the ``gyropipe.well`` schema metadata nested 100,000 deep was a
    RecursionError ("reader failed")."""
    path = tmp_path / "deep.parquet"
    path.write_bytes(parquet_with_metadata(b"gyropipe.well", nested_json(100_000).encode()))
    stderr = refused_by_convert(path, "stations", ".csv")
    assert f"{path}: well metadata ('gyropipe.well' in the schema metadata): {TOO_DEEP}" in stderr


# ------------------------------------------------------- item 11: WITSML in linear time


TOO_LONG = f"is longer than {TEXT_MAX:,} characters (WITSML 1.4.1.1's longest text, a comment, is"
TOO_LONG_TOKEN = "over 8 MiB of one tag or text from its '<' on (no WITSML element comes near)"


@pytest.mark.parametrize(
    ("make", "problem"),
    [
        (lambda: witsml_text(5_000_000), f"the text of <nameWell> {TOO_LONG} 4,000)"),
        (
            lambda: witsml_attribute(4_000_000),
            f"attribute 'note' of <trajectory> {TOO_LONG} 4,000)",
        ),
        (lambda: witsml_text(20_000_000), TOO_LONG_TOKEN),
        (lambda: witsml_attribute(20_000_000), TOO_LONG_TOKEN),
    ],
    ids=["text-5MB", "attribute-4MB", "text-20MB", "attribute-20MB"],
)
def test_witsml_with_huge_text_or_attributes_is_refused_at_its_line_in_linear_time(
    tmp_path: Path, make, problem: str
):
    """Issue 32 item 11: a 20 MB well name took 5.5 s of CPU (text appended per expat chunk),
    an 8 MB attribute over 120 s (expat re-parsing it on every ParseFile chunk); then 0.2 s.
    Fuzz run (seed 1, witsml): a hostile 5 MB line repeated (925 MiB) was read whole before
    its first error (a 1,059 MiB peak), a 5-million-character well name carried into every
    table, header and file written from it; now the file is parsed a MiB at a time, and a
    text or value longer than WITSML ever writes is refused at its line."""
    path = tmp_path / "huge.xml"
    path.write_bytes(make())
    start = time.process_time()
    stderr = refused_by_convert(path, "stations", ".parquet")
    assert time.process_time() - start < 2.0
    assert stderr.startswith(f"error: {path}:2: {problem}") and stderr.count("\n") == 1, stderr


def test_a_huge_witsml_file_is_parsed_without_being_held_whole(tmp_path: Path):
    """Fuzz run (seed 1, witsml #1946): the hostile line repeated, 925 MiB, was read into
    memory whole before its first error (a 1,059 MiB peak); now a MiB at a time. Here
    100 MB of it: Python's allocations stay under 32 MiB (before: over 100 MB)."""
    path = tmp_path / "repeated.xml"
    path.write_bytes(witsml_text(5_000_000) * 20)
    tracemalloc.start()
    try:
        with pytest.raises(InputFileError, match=r"repeated\.xml:2: the text of <nameWell>"):
            load_registry().read(path, "stations")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 32 * 2**20, f"{peak / 2**20:.0f} MiB"


def test_a_witsml_text_of_the_longest_length_is_read_one_more_is_refused(tmp_path: Path):
    """The bound is TEXT_MAX characters of text, the whitespace around them not counted."""
    path = tmp_path / "longest.xml"
    path.write_bytes(witsml_text(TEXT_MAX).replace(b"<nameWell>", b"<nameWell>\n  "))
    table, well = load_registry().read(path, "stations")
    assert table.column("md").to_pylist() == [0.0, 100.0] and well.well == "x" * TEXT_MAX
    path.write_bytes(witsml_text(TEXT_MAX + 1))
    assert "2: the text of <nameWell> is longer than" in refused_by_convert(
        path, "stations", ".csv"
    )


def test_a_witsml_trajectory_of_many_indented_stations_is_read(tmp_path: Path):
    """The whitespace between a container's children is no text of it (a guard): 12,000
    stations indented by 16 spaces are over 10⁵ characters of it in <trajectory>."""
    indent = "\n" + " " * 16
    stations = "".join(
        f'{indent}<trajectoryStation uid="s{i}"><md uom="m">{i}</md><incl uom="dega">1</incl>'
        '<azi uom="dega">10</azi></trajectoryStation>'
        for i in range(12_000)
    )
    head, _, rest = witsml_text(1).decode().partition("<trajectoryStation")
    path = tmp_path / "long.xml"
    path.write_text(head + stations + "\n" + rest[rest.index("</trajectory>") :])
    assert 12_000 * len(indent) > TEXT_MAX
    table, _ = load_registry().read(path, "stations")
    assert table.num_rows == 12_000


# ---------------------------------------------------------- item 16: huge valid inputs


def test_a_csv_header_of_too_many_columns_is_refused_at_its_line(tmp_path: Path):
    """Issue 32 item 16: a 12 MB CSV of 10⁶ columns converted in 26 s of CPU and 973 MB."""
    path = tmp_path / "wide.csv"
    path.write_bytes(csv_wide(MAX_COLUMNS - 2))
    stderr = refused_by_convert(path, "stations", ".parquet")
    assert f"{path}:1: 1,001 columns separated by ',', more than 1,000: refused" in stderr


def test_a_las_file_of_too_many_curves_is_refused_at_its_line(tmp_path: Path):
    """Fuzz campaign (seed 1212, by hand): a 2 MB LAS of 10⁵ curves converted in 12 s and
    660 MB (CSV and Parquet inputs were bounded, LAS was not); refused at curve 1,001."""
    path = tmp_path / "wide.las"
    path.write_bytes(las_wide(MAX_COLUMNS - 3))  # with DEPT, INCL and AZIM: 1,000 curves
    assert load_registry().read(path, "stations")[0].num_rows == 2
    path.write_bytes(las_wide(100_000))
    start = time.process_time()
    stderr = refused_by_convert(path, "log", ".csv")
    assert time.process_time() - start < 2.0
    assert f"{path}:1009: more than 1,000 curves: refused" in stderr  # curve 1,001's line


MEGABYTE = "x" * 1_000_000
LONGEST = "x" * TEXT_MAX
"""The longest header value a reader takes (a megabyte one is refused for its length)."""
HUGE_VALUES = {
    "cell.las": (
        "~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.M 0 :\n STOP.M 100 :\n"
        " NULL. -999.25 :\n~Curve\n DEPT.M : depth\n INCL.DEG : inclination\n"
        f" AZIM.DEG : azimuth (true north)\n~A\n0 0 0\n100 {MEGABYTE} 10\n",
        "cell.las:14 (column 'INCL'): expected a number, got 'xxx",
    ),
    "uom.xml": (
        witsml_text(1).decode().replace('<incl uom="dega">', f'<incl uom="{LONGEST}">', 1),
        "uom.xml:2: <incl>: uom 'xxx",
    ),
    "north.csv": (
        f"North Reference: {LONGEST}\nMD (m),Inc (deg),Azimuth (deg)\n0,0,0\n100,1,10\n",
        "north.csv:1: north reference 'xxx",
    ),
}


@pytest.mark.parametrize("name", sorted(HUGE_VALUES))
def test_a_megabyte_value_is_quoted_by_its_ends_in_a_one_line_error(tmp_path: Path, name: str):
    """Fuzz campaign (seed 1212, by hand): a file's megabyte cell, unit or header value was
    quoted in full, a megabyte error line (every reader, and pipeline values too)."""
    text, where = HUGE_VALUES[name]
    path = tmp_path / name
    path.write_text(text)
    stderr = refused_by_convert(path, "stations", ".csv")
    assert len(stderr) < 500 and stderr.count("\n") == 1, stderr[:1000]
    assert f"{tmp_path}/{where}" in stderr
    chars = 1_000_000 if name == "cell.las" else TEXT_MAX  # a data cell: no header text
    assert "x" * 60 + "…" + "x" * 20 + f"' ({chars:,} characters)" in stderr


def test_a_megabyte_pipeline_value_is_quoted_by_its_ends(tmp_path: Path):
    path = tmp_path / "survey.yaml"
    path.write_text(
        "name: survey\nversion: '1.0'\ninputs:\n  stations: {description: stations}\n"
        f"stages:\n  - id: read\n    uses: read_stations\n    with: {{input: stations, "
        f"reader: {MEGABYTE}}}\n"
    )
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2 and len(result.stderr) < 1000, result.stderr[:1000]
    assert f"{path}:8:" in result.stderr and "' (1,000,000 characters)" in result.stderr


def test_a_long_well_name_no_writer_holds_is_quoted_by_its_ends(tmp_path: Path):
    """Fuzz finding (seed 1212, witsml #335): the WITSML writer's refusal of a megabyte well
    name (it holds 64 characters) quoted the name in full (now the reader refuses a name
    that long: the longest it reads)."""
    path = tmp_path / "named.xml"
    path.write_bytes(witsml_text(TEXT_MAX))
    result = gyropipe_cli("convert", str(path), str(tmp_path / "copy.xml"))
    assert result.returncode == 2 and len(result.stderr) < 500, result.stderr[:1000]
    assert f"{path}: the stations read cannot be written to copy.xml" in result.stderr
    assert "' (65,536 characters) is longer than the 64 characters" in result.stderr
