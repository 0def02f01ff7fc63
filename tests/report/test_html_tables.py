"""The HTML report's tables: each cell escaped as ``html.escape`` escapes it alone, the
flagged cells marked, a row of the wrong length refused."""

from __future__ import annotations

from html import escape

import pytest

from pipeline.reports.document import Column, Table
from pipeline.reports.html import _table

CELLS = (("1 < 2", 'say "hi"'), ("a & b", "it's"), ("\0nul", "plain"), ("", "> 3"))


def table(rows: tuple[tuple[str, ...], ...], cells: frozenset[tuple[int, int]]) -> Table:
    return Table("T", (Column("A"), Column("B", align="left")), rows, cells=cells)


@pytest.mark.parametrize("rows", [CELLS, CELLS[:2] + CELLS[3:], ()])  # with a NUL, without
def test_each_cell_is_escaped_as_alone_and_flagged_where_marked(rows: tuple[tuple[str, ...]]):
    html = _table(table(rows, frozenset({(1, 0)})))
    expected = [
        f'<td class="r{" flag" if i == 1 else ""}">{escape(a)}</td><td class="l">{escape(b)}</td>'
        for i, (a, b) in enumerate(rows)
    ]
    body = html.split("<tbody>\n")[1].split("\n</tbody>")[0]
    assert body.split("\n") == ([f"<tr>{cells}</tr>" for cells in expected] if rows else [""])


def test_a_row_of_the_wrong_length_is_refused():
    with pytest.raises(ValueError, match="row 1 of 'T': 3 cells, not 2"):
        _table(table((("a", "b"), ("a", "b", "c")), frozenset()))
