"""The LAS fast path (``pipeline.io.las.fast``) against the careful path and against
Python's own ``float`` of each cell, on data sections laid out as writers lay them out:
fixed-width columns (the block rewrite keeps their bytes), ragged ones (packed), both in
one file, CRLF and tabs, and blocks small enough that a section spans many of them."""

from __future__ import annotations

import mmap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipeline.errors import InputFileError
from pipeline.io import threads as io_threads
from pipeline.io.las import fast as las_fast
from pipeline.io.las import header as las_header
from pipeline.io.las import read_las
from pipeline.io.las import rows as las_rows

_number = st.one_of(
    st.floats(-1e5, 1e5, allow_nan=False).map(lambda v: round(v, 4)),
    st.integers(-(10**6), 10**6).map(float),
    st.floats(allow_nan=False, allow_infinity=False, width=32).map(float),
)
_formats = st.sampled_from(["{:12.4f}", "{:>14.6e}", "{:>16}", "{:11.2f}"])


def _cell(fmt: str, value: float) -> str:
    text = fmt.format(value) if "{:>16}" not in fmt else f"{value!r:>16}"
    return text if len(text.strip()) < len(text) else " " + text  # a blank between values


@st.composite
def sections(draw: st.DrawFn) -> tuple[list[str], int]:
    """Data lines of n curves: runs of fixed-width lines (one format each), some ragged
    lines, and their n."""
    n = draw(st.integers(1, 6))
    lines: list[str] = []
    for _ in range(draw(st.integers(1, 4))):
        rows = draw(st.lists(st.lists(_number, min_size=n, max_size=n), min_size=1, max_size=30))
        if draw(st.booleans()):
            fmt = draw(_formats)
            lines += ["".join(_cell(fmt, v) for v in row) for row in rows]
        else:
            gap = draw(st.sampled_from([" ", "  ", "\t", " \t "]))
            lines += [gap.join(repr(v) for v in row) for row in rows]
    return lines, n


def _file(tmp_path: Path, lines: list[str], n: int, end: str = "\n") -> Path:
    curves = "".join(f" C{i}.M : curve {i}\n" for i in range(n))
    head = f"~Version\n VERS. 2.0 : v\n WRAP. NO : w\n~Well\n NULL. -1e300 : null\n~Curve\n{curves}"
    path = tmp_path / "log.las"
    path.write_bytes((head + "~A\n" + end.join(lines) + end).encode())
    return path


def _paths(path: Path) -> tuple[tuple[dict[int, np.ndarray], int] | None, las_rows.Data]:
    """The fast path's values (every block's, joined) and row count, or None if it
    declines; and the careful path's rows."""
    source = las_header.load(path)
    header = las_header.parse_header(path, source.header)
    wanted = list(range(len(header.curves)))
    blocks = las_fast.fast_values(source.raw, source.start, len(header.curves), wanted)
    lines = las_header.split_lines(source.raw[source.start :].decode())
    slow = las_rows._slow_values(path, header, lines, source.title_line, wanted)
    if blocks is None:
        return None, slow
    values = {i: np.concatenate([b.values[i] for b in blocks]) for i in wanted}
    return (values, sum(b.rows for b in blocks)), slow


@settings(
    max_examples=80,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    section=sections(),
    block=st.sampled_from([64, 200, 1 << 20]),
    crlf=st.booleans(),
    threads=st.booleans(),
)
def test_fast_path_equals_careful_path_and_float(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    section: tuple[list[str], int],
    block: int,
    crlf: bool,
    threads: bool,
) -> None:
    lines, n = section
    monkeypatch.setattr(las_fast, "BLOCK", block)  # many blocks: layouts change between them
    monkeypatch.setattr(
        io_threads, "reader_threads", lambda: 2 if threads else 1
    )  # blocks read ahead or not
    path = _file(tmp_path, lines, n, "\r\n" if crlf else "\n")
    fast, slow = _paths(path)
    assert fast is not None  # every such layout is read by the fast path
    values, rows = fast
    assert rows == len(lines) == len(slow.lines)
    expected = np.array([[float(cell) for cell in line.split()] for line in lines])
    for i in range(n):
        assert np.array_equal(values[i].view(np.int64), slow.values[i].view(np.int64))
        assert np.array_equal(values[i].view(np.int64), expected[:, i].view(np.int64))


@pytest.mark.parametrize(
    ("bad", "line"),
    [
        ("     1.0000      2.0000     3.00x0", 4),  # text in a fixed-width cell
        ("     1.0000      2.0000           ", 4),  # a missing value in a fixed-width row
        ("     1.0000  2.0000  3.0000  4.0000", 4),  # one value too many
        ("     1.0000      2.0000     1e999 ", 4),  # out of the float range
        ("     1.0000      2.0000       nan ", 4),  # not a number (pyarrow reads NaN)
    ],
)
@pytest.mark.parametrize("threads", [False, True], ids=["one thread", "read ahead"])
def test_a_bad_row_among_fixed_width_blocks_is_located(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, bad: str, line: int, threads: bool
) -> None:
    monkeypatch.setattr(las_fast, "BLOCK", 64)
    monkeypatch.setattr(io_threads, "reader_threads", lambda: 2 if threads else 1)
    good = [f"{i:11.4f}{2 * i:12.4f}{3 * i:11.4f}" for i in range(8)]
    lines = [*good[:3], bad, *good[3:]]
    path = _file(tmp_path, lines, 3)
    first = path.read_text().splitlines().index("~A") + 2
    source = las_header.load(path)
    assert las_fast.fast_values(source.raw, source.start, 3, [0, 1, 2]) is None
    header = las_header.parse_header(path, source.header)
    with pytest.raises(InputFileError) as info:
        list(las_rows.data_blocks(path, source, header, [0, 1, 2]))
    assert info.value.line == first + line - 1


def test_a_large_mapped_file_reads_as_a_small_read_one(tmp_path: Path) -> None:
    """A file past the sniffing size is mapped, not read; its values and lines are those
    of the same rows in a file small enough to be read."""
    rows = [f"{i * 0.5:10.2f}{1000 + i * 0.01:12.4f}{(-1) ** i * i / 7:14.6f}" for i in range(6000)]
    big, small = tmp_path / "big", tmp_path / "small"
    big.mkdir()
    small.mkdir()
    table, _ = read_las(_file(big, rows, 3), "log", None)
    assert isinstance(las_header.load(big / "log.las").raw, mmap.mmap)
    part, _ = read_las(_file(small, rows[:50], 3), "log", None)
    assert table.num_rows == 6000
    assert table.slice(0, 50).equals(part)
    assert table.column("C2").to_pylist()[5999] == float(rows[5999][22:])


@pytest.mark.parametrize("threads", [False, True], ids=["one thread", "read ahead"])
def test_tabs_and_crlf_in_fixed_width_padding_keep_the_layout(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, threads: bool
) -> None:
    """Fixed-width lines ending in CRLF whose padding holds tabs are read as fixed-width
    blocks (no rewrite of the tabs or CRs), each value as ``float`` reads its cell."""
    monkeypatch.setattr(las_fast, "BLOCK", 300)
    monkeypatch.setattr(io_threads, "reader_threads", lambda: 2 if threads else 1)
    lines = [f"{i:10.2f}{-i / 3:14.5f}{i * 1e3:14.1f}" for i in range(60)]
    lines = [line[:11] + "\t" + line[12:] for line in lines]  # padding of the second value
    path = _file(tmp_path, lines, 3, "\r\n")
    source = las_header.load(path)
    width = len(lines[0]) + 2
    block = np.frombuffer(source.raw[source.start : source.start + 4 * width], np.uint8)
    assert las_fast._fixed_width(block.copy(), width, 3) is not None
    fast, slow = _paths(path)
    assert fast is not None
    values, rows = fast
    assert rows == 60
    for i in range(3):
        expected = [float(line.split()[i]) for line in lines]
        assert values[i].tolist() == expected == slow.values[i].tolist()


@pytest.mark.parametrize(
    ("byte", "expected"),
    [("\x0c", "read"), ("\x1f", "read"), ("\r", "error"), ("\x00", "error")],
    ids=["form feed", "unit separator", "lone CR", "NUL"],
)
@pytest.mark.parametrize("at", [10, 15], ids=["separator column", "padding"])
def test_other_control_bytes_in_fixed_width_lines_go_to_the_careful_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, byte: str, expected: str, at: int
) -> None:
    """A control byte that ``pyarrow.csv`` does not trim, in a separator column or in the
    padding of a value, is never written over: the block is declined, and the careful path
    reads it as Python splits a line (form feed and unit separator are whitespace) or
    reports its line."""
    monkeypatch.setattr(las_fast, "BLOCK", 100)
    lines = [f"{i:10.2f}{2 * i:12.4f}{3 * i:11.4f}" for i in range(12)]
    lines[7] = lines[7][:at] + byte + lines[7][at + 1 :]
    path = _file(tmp_path, lines, 3)
    source = las_header.load(path)
    assert las_fast.fast_values(source.raw, source.start, 3, [0, 1, 2]) is None
    header = las_header.parse_header(path, source.header)
    if expected == "read":
        data = list(las_rows.data_blocks(path, source, header, [0, 1, 2]))
        got = np.concatenate([d.values[1] for d in data])
        assert got.tolist() == [float(line.split()[1]) for line in lines]
        return
    with pytest.raises(InputFileError) as info:
        list(las_rows.data_blocks(path, source, header, [0, 1, 2]))
    first = path.read_text().splitlines().index("~A") + 2
    assert info.value.line == first + 7


def test_values_whose_sum_passes_the_float_range_are_read_fast(tmp_path: Path) -> None:
    """Finite values whose sum passes the float range (the fast path's first finiteness
    test) are read by the fast path as ``float`` reads each cell; out-of-range cells are
    reported with their line."""
    lines = [f"{i:6d} {1.7e308:>24.16e} {-1.7e308:>24.16e}" for i in range(5)]
    path = _file(tmp_path, lines, 3)
    fast, _ = _paths(path)
    assert fast is not None
    assert fast[0][1].tolist() == [1.7e308] * 5
    table, _ = read_las(path, "log", None)
    assert table.column("C1").to_pylist() == [1.7e308] * 5
    assert table.column("C2").to_pylist() == [-1.7e308] * 5
    path = _file(tmp_path, [*lines, f"{5:6d} {'1.7e309':>24} {0.0:>24.16e}"], 3)
    with pytest.raises(InputFileError, match="out of range") as info:
        read_las(path, "log", None)
    assert info.value.line == path.read_text().splitlines().index("~A") + 7


@pytest.mark.parametrize(
    ("lines", "n"),
    [
        (["-1000.0", "0.0", "0.0"], 1),  # 8 + 4 + 4 bytes: two "lines" of 8
        (["10.5  2.25", "1 1", "1  3.5"], 2),  # 11 + 4 + 7: a blank column between groups
    ],
)
def test_lines_of_other_lengths_adding_up_to_whole_lines_are_read_fast(
    tmp_path: Path, lines: list[str], n: int
) -> None:
    """A block whose bytes split into lines as long as its first although its lines
    differ is not fixed-width: read by the fast path all the same (packed), as ``float``
    reads each cell."""
    path = _file(tmp_path, lines * 3, n)
    fast, _ = _paths(path)
    assert fast is not None
    values, rows = fast
    assert rows == len(lines) * 3
    for i in range(n):
        assert values[i].tolist() == [float(line.split()[i]) for line in lines * 3]


@pytest.mark.parametrize(
    "odd",
    [
        f"{9.5:8.4f}{8.25:14.4f}{7.125:12.4f}",  # the same width, values laid out elsewhere
        f"{9.5:10.4f} {1234567.25:12.4f}{7.125:11.4f}",  # a value over a separator column
        f"{'9.50001238.2500':>18}{7.125:16.4f}",  # two values run together over it
    ],
)
def test_a_line_laid_out_otherwise_after_the_sampled_lines_is_read_as_written_or_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, odd: str
) -> None:
    """The layout comes from a block's first SAMPLE lines; a line after them as long but
    laid out otherwise is read as its whitespace-separated numbers say, or the block goes
    to the careful path, which reads it so or names its line: never another number."""
    monkeypatch.setattr(las_fast, "SAMPLE", 4)
    good = [f"{i:11.4f}{2 * i:12.4f}{3 * i:11.4f}" for i in range(8)]
    assert all(len(line) == len(odd) for line in good)
    lines = [*good[:6], odd, *good[6:]]
    path = _file(tmp_path, lines, 3)
    cells = [line.split() for line in lines]
    if any(len(row) != 3 for row in cells):  # not three numbers: refused at its line
        source = las_header.load(path)
        header = las_header.parse_header(path, source.header)
        first = path.read_text().splitlines().index("~A") + 2
        with pytest.raises(InputFileError) as info:
            list(las_rows.data_blocks(path, source, header, [0, 1, 2]))
        assert info.value.line == first + 6
        return
    fast, slow = _paths(path)
    expected = np.array([[float(cell) for cell in row] for row in cells])
    for i in range(3):
        assert np.array_equal(slow.values[i], expected[:, i])
        if fast is not None:
            assert np.array_equal(fast[0][i], expected[:, i])
