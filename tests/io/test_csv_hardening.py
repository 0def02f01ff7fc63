"""Hardening of the CSV reader (fuzz findings): numbers that overflow to ±inf are refused
like NaN, and a binary file is refused after its first block, without reading it all."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pyarrow as pa
import pytest

from pipeline.errors import InputFileError
from pipeline.io import csv as csv_plugin
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli, plugin_io

READER, _ = plugin_io(csv_plugin)


def put(tmp_path: Path, content: str | bytes, name: str = "survey.csv") -> Path:
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def read(path: Path, **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, "stations", READER.options.model_validate(options))


def failure(path: Path, **options: Any) -> InputFileError:
    with pytest.raises(InputFileError) as info:
        read(path, **options)
    return info.value


@pytest.mark.parametrize("cell", ["1e999", "-1e999", "1" * 400, "1e400"])
def test_overflowing_number(tmp_path: Path, cell: str) -> None:
    err = failure(put(tmp_path, f"MD[m],INC[deg],AZI TN[deg]\n0,0,0\n100,1,{cell}\n"))
    assert (err.line, err.column) == (3, "AZI TN[deg]")
    assert "expected a finite number" in str(err)


def test_overflowing_number_with_decimal_commas(tmp_path: Path) -> None:
    err = failure(put(tmp_path, "MD[m];INC[deg];AZI TN[deg]\n0;0;0\n100;1,5;2,5e999\n"))
    assert (err.line, err.column) == (3, "AZI TN[deg]")
    assert "expected a finite number, got '2,5e999'" in str(err)


class CountingOpen:
    """Patches ``Path.open`` to count the bytes read from every file it opens."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.read = 0
        original = Path.open

        def open_counting(path: Path, *args: Any, **kwargs: Any) -> Any:
            fh = original(path, *args, **kwargs)
            real_read = fh.read

            def read(size: int = -1) -> Any:
                data = real_read(size)
                self.read += len(data)
                return data

            fh.read = read
            return fh

        monkeypatch.setattr(Path, "open", open_counting)


def test_binary_file_refused_after_its_first_block(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A 1 GiB all-NUL file was read whole (1.2 GB RSS) before the NUL byte error."""
    path = tmp_path / "nul.csv"
    with path.open("wb") as fh:
        fh.truncate(50 * 2**20)  # sparse: 50 MiB of NUL bytes
    counting = CountingOpen(monkeypatch)
    err = failure(path)
    assert err.line == 1 and "NUL byte" in str(err)
    assert 0 < counting.read <= 2 * 64 * 1024
    monkeypatch.undo()
    result = gyropipe_cli("convert", str(path), str(tmp_path / "o.parquet"), "--kind", "stations")
    assert result.returncode == 1
    assert f"{path}:1: NUL byte: this is not a text CSV file" in result.stderr


def test_invalid_utf8_in_the_first_block_is_refused_at_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = put(tmp_path, "MD[m],INC[deg],AZI TN[deg]\n" + "1,2,3\n" * 20_000 + "\u00e9" * 10)
    with path.open("r+b") as fh:  # a lone continuation byte on line 5
        fh.seek(27 + 6 * 3 + 2)
        fh.write(b"\x80")
    counting = CountingOpen(monkeypatch)
    err = failure(path)
    assert err.line == 5 and "not UTF-8" in str(err)
    assert counting.read <= 64 * 1024


def test_character_cut_by_the_first_block_is_no_error(tmp_path: Path) -> None:
    """A two-byte character across the end of the checked block is valid UTF-8."""
    head = "MD[m],INC[deg],AZI TN[deg],Note\n"
    row = "1,2,3,x\n"
    rows = (64 * 1024 - len(head) - 1) // len(row)
    filler = "y" * (64 * 1024 - len(head) - rows * len(row) - 1 - len("4,5,6,"))
    text = head + row * rows + "4,5,6," + filler + "\u00e9\n" + "7,8,9,z\n"
    data = text.encode()
    assert data[64 * 1024 - 1 : 64 * 1024 + 1] == "\u00e9".encode()
    table, _ = read(put(tmp_path, data), columns={"md": "MD[m]"})
    assert table.num_rows == rows + 2
