"""The CSV reader's fast path (file mapped and checked block by block, rows parsed typed by
``pyarrow.csv`` in one pass) against Python's ``float`` of each cell and against its
locating path (every cell parsed as a string, then checked and converted), on files small
and large (past the first block, so mapped), with varied layouts; and problems deep in a
large file located on their line. Large files are read in one block, and in small blocks
parsed on one thread or on three threads a few blocks ahead (as when cores are idle)."""

from __future__ import annotations

import mmap
import random
from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputFileError
from pipeline.io import threads as io_threads
from pipeline.io.csv import LAYOUTS, read
from pipeline.io.csv import rows as csv_rows
from pipeline.io.csv.header import HEADER_SEARCH_LINES, find_header
from pipeline.io.csv.options import CsvOptions

NAMES = ("time", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z")
HEADER = ("time [s]", *(f"gyro_{a} [deg/h]" for a in "xyz"), *(f"acc_{a} [m/s2]" for a in "xyz"))
LAYOUTS_TRIED = [  # delimiter, line end, byte-order mark, title lines, quotes, extras
    (",", "\n", False, 0, False, ""),
    (";", "\n", False, 3, False, "comment"),
    ("\t", "\r\n", False, 1, False, ""),
    ("|", "\n", True, 2, True, "blank"),
    (",", "\n", False, 4, True, "footer"),
    (";", "\n", False, 0, False, "decimal comma"),
    (",", "\n", False, 2, False, "no final line end"),
]


BLOCKS = ["one block", "small blocks, one thread", "small blocks, three threads"]


@pytest.fixture(params=BLOCKS)
def blocks(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """How the rows are parsed: in one block (the default size), or in blocks of 16 KiB (a
    dozen in a large file) on one thread or on three."""
    if request.param != BLOCKS[0]:
        monkeypatch.setattr(csv_rows, "ROWS_BLOCK", 16 * 1024)
        threads = 3 if request.param == BLOCKS[2] else 1
        monkeypatch.setattr(io_threads, "reader_threads", lambda: threads)
    return str(request.param)


def _cell(rng: random.Random) -> str:
    value = rng.choice([rng.uniform(-1e3, 1e3), rng.gauss(0, 1e-3), float(rng.randint(-99, 99))])
    return rng.choice([repr(value), f"{value:.4f}", f"{value:.6e}", f"{value:+.9g}"])


def _file(
    path: Path, rows: int, layout: tuple[str, str, bool, int, bool, str], seed: int
) -> tuple[list[list[str]], list[int]]:
    """Write a samples CSV; its cells (as written, one list per row) and their lines."""
    delimiter, end, bom, title, quoted, extra = layout
    rng = random.Random(seed)
    lines = ["Operator: Gyro Ølsen", *(f"Remark {i} — raw data" for i in range(title - 1))][:title]
    lines.append(delimiter.join(f'"{h}"' if quoted else h for h in HEADER))
    cells, numbers = [], []
    for row in range(rows):
        if extra == "comment" and row % 97 == 5:
            lines.append(f"# pause {row}")
        if extra == "blank" and row % 89 == 7:
            lines.append("")
        values = [f"{row * 0.01:.2f}", *(_cell(rng) for _ in NAMES[1:])]
        if extra == "decimal comma":
            values = [v.replace(".", ",") for v in values]
        cells.append(values)
        shown = [f'"{v}"' if quoted and i % 3 == 1 else v for i, v in enumerate(values)]
        lines.append(delimiter.join(shown))
        numbers.append(len(lines))
    if extra == "footer":
        lines.append("End of survey")
    text = end.join(lines) + ("" if extra == "no final line end" else end)
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + text.encode())
    if extra == "decimal comma":
        cells = [[v.replace(",", ".") for v in row] for row in cells]
    return cells, numbers


def _locating_path(path: Path) -> dict[str, np.ndarray]:
    """The columns as the locating path reads them: strings first, then converted."""
    layout = LAYOUTS["samples"]
    text = csv_rows.load(path, HEADER_SEARCH_LINES)
    header = find_header(path, text.head, CsvOptions(), layout.required)
    chosen = {name: header.found[name][0] for name in NAMES}
    rows = csv_rows.data_rows(path, text, header, [chosen[n].index for n in layout.required])
    decimal = "." if header.delimiter == "," else csv_rows.decimal_of(path, rows, header, chosen)
    rows = csv_rows._without_skipped(rows)
    names = [f"c{i}" for i in range(len(header.cells))]
    wanted = {name: names[cell.index] for name, cell in chosen.items()}
    strings = csv_rows._strings(path, rows, header, names, wanted)
    types = layout.types()
    return {
        name: csv_rows._converted(
            path, strings[name], types[name], False, decimal, rows, chosen[name].text
        ).to_numpy(zero_copy_only=False)
        for name in NAMES
    }


@pytest.mark.parametrize("rows", [40, 2500])
@pytest.mark.parametrize("layout", LAYOUTS_TRIED, ids=lambda layout: repr(layout[:2] + layout[5:]))
def test_fast_path_equals_float_and_the_locating_path(
    tmp_path: Path, rows: int, layout: tuple[str, str, bool, int, bool, str], blocks: str
) -> None:
    path = tmp_path / "samples.csv"
    cells, lines = _file(path, rows, layout, seed=rows + len(layout[5]))
    assert (path.stat().st_size > csv_rows.BLOCK) == (rows > 100)
    mapped = rows > 100 and not layout[2] and layout[1] == "\n"  # no BOM, no CR
    assert isinstance(csv_rows.load(path, HEADER_SEARCH_LINES).data, mmap.mmap) == mapped
    table, _ = read(path, "samples", None)
    located = _locating_path(path)
    for i, name in enumerate(NAMES):
        values = table.column(name).to_numpy()
        expected = np.array([float(row[i]) for row in cells])
        assert np.array_equal(values.view(np.int64), expected.view(np.int64)), name
        assert np.array_equal(values.view(np.int64), located[name].view(np.int64)), name
    assert table.column("source_line").to_pylist() == lines


def _large(tmp_path: Path) -> tuple[Path, list[str]]:
    path = tmp_path / "samples.csv"
    _file(path, 3000, LAYOUTS_TRIED[0], seed=1)
    return path, path.read_text().split("\n")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda cells: cells.__setitem__(3, "1.5x"), "expected a number, got '1.5x'"),
        (lambda cells: cells.__setitem__(5, ""), "expected a number, got an empty cell"),
        (lambda cells: cells.__setitem__(2, "1e999"), "too large for a 64-bit float"),
        (lambda cells: cells.__setitem__(4, "nan"), "expected a number, got 'nan'"),
        (lambda cells: cells.append("7"), "expected 7 cells as in the header"),
    ],
)
def test_a_bad_cell_deep_in_a_large_file_is_located(
    tmp_path: Path, change: object, message: str, blocks: str
) -> None:
    path, lines = _large(tmp_path)
    cells = lines[2400].split(",")
    change(cells)  # type: ignore[operator]
    lines[2400] = ",".join(cells)
    path.write_text("\n".join(lines))
    with pytest.raises(InputFileError) as info:
        read(path, "samples", None)
    assert message in str(info.value)
    assert info.value.line == 2401


@pytest.mark.parametrize(
    ("bad", "message"),
    [(b"\0", "NUL byte"), (b"\xff", "not UTF-8 text"), (b"\xc3", "not UTF-8 text")],
)
def test_a_binary_byte_deep_in_a_large_file_is_located(
    tmp_path: Path, bad: bytes, message: str, blocks: str
) -> None:
    path, lines = _large(tmp_path)
    data = "\n".join(lines).encode()
    at = data.index(b"\n", len(data) * 3 // 4) + 4  # in the first cell (time) of a row
    path.write_bytes(data[:at] + bad + data[at:])
    with pytest.raises(InputFileError) as info:
        read(path, "samples", None)
    assert message in str(info.value)
    assert info.value.line == data.count(b"\n", 0, at) + 1


def test_crlf_line_ends_past_the_first_block_read_as_lf(tmp_path: Path, blocks: str) -> None:
    """A mapped file whose later lines end with CRLF (checked block by block as they are
    parsed, not before) reads as the same file with LF line ends."""
    path, lines = _large(tmp_path)
    plain, _ = read(path, "samples", None)
    path.write_text("\n".join(lines[:2000]) + "\n" + "\r\n".join(lines[2000:]))
    assert isinstance(csv_rows.load(path, HEADER_SEARCH_LINES).data, mmap.mmap)
    mixed, _ = read(path, "samples", None)
    assert mixed.equals(plain)


def test_units_converted_in_every_block_equal_float_times_the_factor(
    tmp_path: Path, blocks: str
) -> None:
    """Rates in deg/s and accelerations in g (converted in place once parsed) equal
    Python's ``float`` of each cell times 3600 or 9.80665, in blocks parsed typed and in
    blocks holding a comment line (parsed as strings, then converted)."""
    rng = random.Random(5)
    header = ("time [s]", *(f"gyro_{a} [deg/s]" for a in "xyz"), *(f"acc_{a} [g]" for a in "xyz"))
    lines, cells = [",".join(header)], []
    for row in range(3000):
        if row % 700 == 3:
            lines.append("# a note")
        values = [f"{row * 0.01:.2f}", *(_cell(rng) for _ in NAMES[1:])]
        cells.append(values)
        lines.append(",".join(values))
    path = tmp_path / "samples.csv"
    path.write_text("\n".join(lines) + "\n")
    table, _ = read(path, "samples", None)
    factors = {"time": 1.0} | dict.fromkeys(NAMES[1:4], 3600.0) | dict.fromkeys(NAMES[4:], 9.80665)
    for i, name in enumerate(NAMES):
        expected = np.array([float(row[i]) * factors[name] for row in cells])
        assert np.array_equal(table.column(name).to_numpy(), expected), name
