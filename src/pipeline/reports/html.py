"""A :class:`~pipeline.reports.document.Document` as one self-contained HTML file: CSS
inline, figures as inline SVG in the font their text was measured with (embedded:
:mod:`~pipeline.reports.web_fonts`), no script, and a Content-Security-Policy that forbids
the page any network fetch."""

from __future__ import annotations

from collections.abc import Iterator
from html import escape

from pipeline.reports.document import (
    Block,
    Document,
    Fields,
    Paragraph,
    Plot,
    Section,
    Table,
    Verdict,
)
from pipeline.reports.figures import Figures
from pipeline.reports.web_fonts import font_faces

CSP = "default-src 'none'; style-src 'unsafe-inline'; font-src data:"

CSS = """
:root { --ink:#1f2933; --muted:#616e7c; --navy:#1b365d; --rule:#d5dbe3; --zebra:#f5f7fa;
  --ok:#23867a; --warn:#b7791f; --fail:#c0392b; --info:#2f6fb0; }
* { box-sizing: border-box; }
html { background: #e9edf2; }
body { margin: 0; font: 13px/1.45 "DejaVu Sans", "Liberation Sans", Arial, sans-serif;
  color: var(--ink); }
.page { max-width: 1000px; margin: 24px auto; background: #fff; padding: 36px 44px 28px;
  box-shadow: 0 1px 4px rgba(0,0,0,.12); }
.title-block { border-top: 6px solid var(--navy); padding-top: 14px; margin-bottom: 18px;
  display: flex; justify-content: space-between; align-items: flex-end; gap: 24px; }
.title-block h1 { margin: 0; font-size: 26px; color: var(--navy); letter-spacing: .2px; }
.title-block .subject { font-size: 20px; font-weight: bold; margin: 4px 0 0; }
.title-block .subtitle { color: var(--muted); margin: 2px 0 0; }
.title-block .issued { text-align: right; color: var(--muted); font-size: 12px; }
.brand { font-weight: bold; color: var(--navy); font-size: 12px; letter-spacing: 2px;
  text-transform: uppercase; }
nav.toc { border: 1px solid var(--rule); background: var(--zebra); padding: 8px 14px;
  font-size: 12px; margin-bottom: 8px; }
nav.toc a { color: var(--navy); text-decoration: none; margin-right: 14px;
  white-space: nowrap; }
h2 { font-size: 16px; color: var(--navy); border-bottom: 2px solid var(--navy);
  padding-bottom: 3px; margin: 28px 0 12px; }
h3 { font-size: 13px; color: var(--navy); margin: 14px 0 6px; }
.fields-group { display: grid; grid-template-columns: repeat(auto-fit, minmax(260px, 1fr));
  gap: 6px 28px; }
dl { display: grid; grid-template-columns: max-content 1fr; gap: 2px 14px; margin: 0; }
dt { color: var(--muted); }
dd { margin: 0; font-weight: 600; overflow-wrap: anywhere; }
table { border-collapse: collapse; width: 100%; font-size: 12px;
  font-variant-numeric: tabular-nums; }
th { background: var(--navy); color: #fff; font-weight: 600; padding: 4px 6px;
  vertical-align: bottom; position: sticky; top: 0; }
th .unit { display: block; font-weight: normal; font-size: 10.5px; opacity: .85; }
td { padding: 2px 6px; border-bottom: 1px solid #eef1f4; }
tbody tr:nth-child(even) td { background: var(--zebra); }
tbody tr.marked td { background: #fbe3e0; }
table tbody tr td.flag { background: #fcebc0; box-shadow: inset 3px 0 0 #d9a21b; }
td { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
.r { text-align: right; white-space: nowrap; }
.l { text-align: left; }
.w { overflow-wrap: break-word; min-width: 11em; }
table.listing { font-size: 11px; }
table.listing th, table.listing td { padding-left: 4px; padding-right: 4px; }
table.compact { width: auto; min-width: 50%; }
.note { color: var(--muted); font-size: 11.5px; margin: 4px 0 10px; }
.verdict { border-left: 5px solid var(--info); background: #eef4fb; padding: 7px 12px;
  margin: 8px 0; font-weight: 600; }
.verdict.ok { border-color: var(--ok); background: #e6f4f1; }
.verdict.warn { border-color: var(--warn); background: #fdf4e3; }
.verdict.fail { border-color: var(--fail); background: #fbe9e7; }
figure { margin: 14px 0 18px; break-inside: avoid; }
figure svg { display: block; max-width: 100%; height: auto; margin: 0 auto;
  font-kerning: normal; font-variant-ligatures: none; }
figcaption { font-size: 11.5px; color: var(--muted); margin-top: 4px; }
figcaption b { color: var(--ink); }
footer { margin-top: 28px; border-top: 1px solid var(--rule); padding-top: 6px;
  color: var(--muted); font-size: 11px; }
@media print {
  html { background: #fff; }
  .page { box-shadow: none; margin: 0; max-width: none; padding: 0; }
  nav.toc { display: none; }
  @page { size: A4; margin: 14mm 12mm; }
}
"""


def render_html(doc: Document, drawn: Figures | None = None) -> bytes:
    """The report as one HTML page that needs nothing but itself (figures from ``drawn``,
    shared with the PDF), UTF-8: the embedded fonts (ASCII, a third of the page) encoded apart
    from the text around them (whose non-Latin-1 characters make encoding it cost 2 ns a
    character)."""
    drawn = drawn or Figures()
    figures = iter(range(1, len(doc.plots()) + 1))
    sections = "\n".join(_section(s, i, figures, drawn) for i, s in enumerate(doc.sections, 1))
    toc = " ".join(
        f'<a href="#{_anchor(s, i)}">{i}. {escape(s.title)}</a>'
        for i, s in enumerate(doc.sections, 1)
    )
    head = f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="{CSP}">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{escape(doc.title)} — {escape(doc.subject)}</title>
<style>"""
    body = f"""{CSS}</style>
</head>
<body>
<main class="page">
<header class="title-block">
<div>
<div class="brand">gyropipe</div>
<h1>{escape(doc.title)}</h1>
<p class="subject">{escape(doc.subject)}</p>
<p class="subtitle">{escape(doc.subtitle)}</p>
</div>
<div class="issued">{escape(doc.issued)}</div>
</header>
<nav class="toc">{toc}</nav>
{sections}
<footer>{escape(doc.footer)}</footer>
</main>
</body>
</html>
"""
    return b"".join((head.encode(), font_faces().encode("ascii"), body.encode()))


def _anchor(section: Section, number: int) -> str:
    return section.key or f"section-{number}"


def _section(section: Section, number: int, figures: Iterator[int], drawn: Figures) -> str:
    parts = [
        f'<section id="{_anchor(section, number)}">',
        f"<h2>{number}. {escape(section.title)}</h2>",
    ]
    fields: list[str] = []
    for block in section.blocks:
        if isinstance(block, Fields):
            fields.append(_fields(block))
            continue
        if fields:
            parts.append(f'<div class="fields-group">{"".join(fields)}</div>')
            fields = []
        parts.append(_block(block, figures, drawn))
    if fields:
        parts.append(f'<div class="fields-group">{"".join(fields)}</div>')
    parts.append("</section>")
    return "\n".join(parts)


def _block(block: Block, figures: Iterator[int], drawn: Figures) -> str:
    if isinstance(block, Table):
        return _table(block)
    if isinstance(block, Verdict):
        return f'<p class="verdict {block.level}">{escape(block.text)}</p>'
    if isinstance(block, Paragraph):
        return f'<p class="note">{escape(block.text)}</p>'
    if isinstance(block, Plot):
        return _figure(block, next(figures), drawn)
    raise TypeError(f"not a report block: {block!r}")


def _fields(block: Fields) -> str:
    rows = "".join(f"<dt>{escape(k)}</dt><dd>{escape(v)}</dd>" for k, v in block.items)
    return f"<div><h3>{escape(block.title)}</h3><dl>{rows}</dl></div>"


def _table(table: Table) -> str:
    units = any(c.unit for c in table.columns)
    head = "".join(
        f'<th class="{"r" if c.align == "right" else "l"}">{escape(c.header)}'
        + (f'<span class="unit">{escape(c.unit) or "&nbsp;"}</span>' if units else "")
        + "</th>"
        for c in table.columns
    )
    classes = ["r" if c.align == "right" else ("l w" if c.wrap else "l") for c in table.columns]
    flagged: dict[int, set[int]] = {}
    for i, j in table.cells:
        flagged.setdefault(i, set()).add(j)
    formats: dict[frozenset[int], str] = {}  # a row's cells by its flagged columns

    def cells(i: int, row: list[str]) -> str:
        if len(row) != len(classes):
            raise ValueError(f"row {i} of {table.title!r}: {len(row)} cells, not {len(classes)}")
        marks = frozenset(flagged.get(i, ()))
        found = formats.get(marks)
        if found is None:
            found = formats[marks] = "".join(
                f'<td class="{k}{" flag" if j in marks else ""}">{{}}</td>'
                for j, k in enumerate(classes)
            )
        return found.format(*row)

    body = "\n".join(
        ('<tr class="marked">' if i in table.marked else "<tr>") + cells(i, row) + "</tr>"
        for i, row in enumerate(_escaped(table.rows))
    )
    compact = "" if len(table.columns) > 4 or table.kind == "listing" else " compact"
    title = f"<h3>{escape(table.title)}</h3>" if table.title else ""
    note = f'<p class="note">{escape(table.note)}</p>' if table.note else ""
    return (
        f'{title}<table class="{escape(table.kind)}{compact}">'
        f"<thead><tr>{head}</tr></thead><tbody>\n{body}\n</tbody></table>{note}"
    )


NUL = chr(0)
"""What :func:`_escaped` joins cells by: a character :func:`~html.escape` leaves as it is and
no report text holds (``chr``: the report code's literals are what the fonts must map)."""


def _escaped(rows: tuple[tuple[str, ...], ...]) -> list[list[str]]:
    """Each row's cells escaped for HTML, by one :func:`~html.escape` of all the cells
    joined by :data:`NUL` where no cell holds one."""
    joined = NUL.join(v for row in rows for v in row)
    if joined.count(NUL) != sum(map(len, rows)) - 1:  # a NUL in a cell (or no cell)
        return [list(map(escape, row)) for row in rows]
    texts = escape(joined).split(NUL)
    out, start = [], 0
    for row in rows:
        out.append(texts[start : start + len(row)])
        start += len(row)
    return out


def _figure(plot: Plot, number: int, drawn: Figures) -> str:
    return (
        f'<figure id="fig-{escape(plot.key)}" class="plot">{drawn.svg(plot)}'
        f"<figcaption><b>Figure {number}. {escape(plot.title)}.</b> {escape(plot.caption)}"
        "</figcaption></figure>"
    )
