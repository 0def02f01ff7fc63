"""The fleet page: one self-contained HTML page of a batch output directory for whoever
manages the work — wells counted by status, then one row per well, failing wells first,
with its QC checks and stations dropped, acceptance gates, worst clearance separation
factor, drift rate, TD, largest dogleg severity and a link to its report
(:mod:`pipeline.batch.fleet`).

Every batch writes it as ``OUT/fleet.html`` (:func:`pipeline.batch.summary.write_summary`);
``gyropipe status DIR --html`` writes it from the ledger. A batch takes the figures of the
wells it ran from their workers (each records its well's as the run ends), so the batch
process reads no well's outputs for it. No script, no request: styles are
inline, links are relative; statuses are told in words and symbols as well as colours
(Okabe–Ito, safe for colour-blind readers); every text from the wells is escaped.
"""

from __future__ import annotations

import datetime as dt
import html
import os
import time
import urllib.parse
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from pipeline.atomic import atomic_write_bytes
from pipeline.errors import file_errors
from pipeline.qc.dropped import Dropped
from pipeline.qc.gates import FAIL, PASS
from pipeline.qc.verdict import SHOWN
from pipeline.reports.check_titles import check_title, printed_unit
from pipeline.reports.numbers import UNDEFINED, fmt, fmt_measured, fmt_sig, fmt_sigma
from pipeline.tables import DLS_UNIT

from .causes import plain_cause
from .fleet import WellFigures, well_figures
from .records import BatchRow

FLEET_PAGE = "fleet.html"
NONE = "—"
"""a figure the well does not have"""
ORDER = ("failed", "interrupted", "stale", "running", "rejected", "done", "skipped")
"""statuses in the order the page lists them: failing wells first"""
COUNTED = ("done", "rejected", "failed", "interrupted", "skipped", "not run")
WORDS = {
    "failed": ("✖", "Failed"),
    "interrupted": ("■", "Interrupted"),
    "stale": ("■", "Stopped (its batch is gone)"),
    "running": ("▶", "Running"),
    "rejected": ("▲", "Rejected"),
    "done": ("✔", "Done"),
    "skipped": ("○", "Skipped"),
    "not run": ("·", "Not run"),
}
CLEARANCE_WORDS = {"pass": ("✔", "pass"), "warn": ("▲", "caution"), "fail": ("✖", "stop")}
PUBLISHED = frozenset({"done", "rejected", "skipped"})
"""statuses whose well has published outputs to read figures from"""


@dataclass(frozen=True)
class FleetWell:
    """A well's row: what happened to it and where its outputs are published."""

    well: str
    status: str
    """done, rejected, failed, interrupted, skipped, running or stale"""
    detail: str
    """the error (failed), the failed gates (rejected), why it was skipped…"""
    time_s: float | None
    """wall time of its run, s"""
    run_id: int | None
    """the run whose outputs the well's figures must come from (None: any)"""
    well_dir: Path
    figures: WellFigures | None = None
    """its figures as the worker that ran it read them (None: read from ``well_dir``)"""


@dataclass(frozen=True)
class Fleet:
    """What the page shows: its title, the batches it covers, the wells."""

    title: str
    batches: tuple[BatchRow, ...]
    wells: tuple[FleetWell, ...]
    not_run: int = 0
    """wells of the batch it never came to"""
    ended: float | None = None
    """when the batch ended, POSIX s (its page is written before the ledger row says so)"""
    ledger_id: str | None = None
    """the identity of the ledger whose runs the wells' ``run_id`` are"""


def fleet_title(out_dir: Path) -> str:
    """The title of the page of every well of ``out_dir``."""
    return f"Wells in {out_dir.resolve().name or out_dir}"


def write_fleet_page(fleet: Fleet, path: Path) -> Path:
    """Write the page of ``fleet`` to ``path`` atomically; returns ``path``. Raises
    :class:`~pipeline.errors.GyropipeError` naming the file if it cannot be written."""
    page = fleet_html(fleet, path.parent).encode()
    with file_errors("write the fleet page", path):
        atomic_write_bytes(path, page)
    return path


def fleet_html(fleet: Fleet, page_dir: Path) -> str:
    """The page (module docstring); report links relative to ``page_dir``."""
    rows = sorted(fleet.wells, key=lambda w: (_rank(w.status), w.well))
    figures = [_figures(w, fleet.ledger_id) for w in rows]
    tally = Counter(w.status for w in fleet.wells)
    tally["not run"] += fleet.not_run
    body = "\n".join(_row(w, f, page_dir) for w, f in zip(rows, figures, strict=True))
    pipelines = sorted({f.pipeline for f in figures if f.pipeline}) or sorted(
        {Path(b.pipeline_file).stem for b in fleet.batches}
    )
    title = f"{fleet.title}: {_plural(len(fleet.wells) + fleet.not_run, 'well')}"
    return PAGE.format(
        title=_e(title),
        about=_about(fleet, pipelines),
        bar=_bar(tally),
        counts=_counts(tally),
        rows=body or f'<tr><td colspan="{len(HEADS)}">No wells.</td></tr>',
        heads="".join(f'<th scope="col"{a}>{h}</th>' for h, a in HEADS),
    )


FIGURE_HEADS = (
    ("QC checks", ""),
    ("Acceptance", ""),
    ("Clearance: least SF", ""),
    ("Drift", ""),
    ('TD MD <span class="u">m</span>', ' class="n"'),
    ('TD TVD <span class="u">m</span>', ' class="n"'),
    (f'Max DLS <span class="u">{printed_unit(DLS_UNIT)}</span>', ' class="n"'),
)
"""the columns of a well's figures (one cell saying why where it has none)"""
HEADS = (
    ("Well", ""),
    ("Status", ""),
    *FIGURE_HEADS,
    ('Time <span class="u">s</span>', ' class="n"'),
    ("Report", ""),
)


def _figures(well: FleetWell, ledger_id: str | None) -> WellFigures:
    """A well's figures: the worker's, else read from its published outputs (run
    ``well.run_id`` of ledger ``ledger_id``)."""
    if well.figures is not None:
        return well.figures
    if well.status not in PUBLISHED:
        return WellFigures()
    return well_figures(well.well_dir, well.run_id, ledger_id=ledger_id)


def _row(well: FleetWell, figures: WellFigures, page_dir: Path) -> str:
    symbol, word = WORDS.get(well.status, ("?", well.status))
    status = f'<span class="sym" aria-hidden="true">{symbol}</span> {_e(word)}'
    detail = _detail(well)
    if detail:
        status += f'<div class="why">{_e(detail)}</div>'
    for problem in figures.problems:
        status += f'<div class="why problem">Output: {_e(problem)}</div>'
    cells = [f'<th scope="row">{_e(well.well)}</th>', f'<td class="st">{status}</td>']
    if figures.missing:
        span = len(FIGURE_HEADS)
        cells.append(f'<td colspan="{span}" class="problem">{_e(figures.missing)}</td>')
    else:
        cells += [
            f"<td>{_qc(figures)}</td>",
            f"<td>{_gates(figures)}</td>",
            f"<td>{_clearance(figures)}</td>",
            f"<td>{_drift(figures)}</td>",
            _number(figures.td_md, 1),
            _number(figures.td_tvd, 1),
            _dls(figures),
        ]
    cells += [_number(well.time_s, 1), f"<td>{_links(well.well_dir, figures, page_dir)}</td>"]
    return f'<tr class="s-{_e(well.status)}">{"".join(cells)}</tr>'


def _dropped_by(dropped: Dropped) -> str:
    """What dropped a station, in the checks' titles (compassing: that it found no solution)."""
    titles = [check_title(name, name).title for name in dropped.checks]
    return ", ".join(titles) if titles else "compassing found no solution"


def _detail(well: FleetWell) -> str:
    """The error or reason in a reader's words: a failure without the stage that raised it
    and its error class, paths shortened to file names; none for a well done."""
    if well.status == "done":
        return ""
    if well.status == "rejected":
        return "survey not accepted"
    return plain_cause(well.detail)


def _qc(figures: WellFigures) -> str:
    """The checks passed or failed, then the stations dropped (recorded, not in the
    trajectory) with their MDs and what dropped them."""
    qc = figures.qc
    if qc is None:
        return NONE
    if not qc.failures:
        said = f'<span class="ok">✔</span> {qc.evaluated} passed' if qc.evaluated else NONE
    else:
        which = ", ".join(f"{check_title(n, n).title} {k}" for n, k in qc.failed.most_common())
        said = (
            f'<span class="bad">✖</span> {qc.failures} of {qc.evaluated} failed'
            f'<div class="why">{_e(which)}</div>'
        )
    if qc.dropped:
        shown = "; ".join(f"MD {d.md:.2f} m: {_dropped_by(d)}" for d in qc.dropped[:SHOWN])
        more = f"; and {len(qc.dropped) - SHOWN} more" if len(qc.dropped) > SHOWN else ""
        said += (
            f'<div class="why dropped"><span class="bad">▲</span> '
            f"{_plural(len(qc.dropped), 'station')} dropped ({_e(shown + more)})</div>"
        )
    return said


def _gates(figures: WellFigures) -> str:
    gates = figures.gates
    if gates is None:
        return NONE
    failed = [g for g in gates if g.status == FAIL]
    unknown = sum(g.status not in (PASS, FAIL) for g in gates)
    extra = f'<div class="why">{unknown} not evaluated</div>' if unknown else ""
    if not failed:
        passed = len(gates) - unknown
        return f'<span class="ok">✔</span> {passed} passed{extra}'
    names = ", ".join(
        f'<span title="{_e(g.description)}">{_e(_words(g.name))}</span>' for g in failed
    )
    return f'<span class="bad">✖</span> failed: {names}{extra}'


def _clearance(figures: WellFigures) -> str:
    worst = figures.clearance
    if worst is None:
        return NONE
    symbol, word = CLEARANCE_WORDS.get(worst.level, ("?", worst.level))
    tone = "ok" if worst.level == "pass" else "bad"
    sf = UNDEFINED if worst.sf == float("-inf") else fmt(worst.sf, 2)
    return (
        f'<span class="{tone}">{symbol}</span> {sf} ({word})'
        f'<div class="why">against {_e(worst.offset)} at {fmt(worst.md, 1)} m MD</div>'
    )


def _drift(figures: WellFigures) -> str:
    if not figures.drift:
        return NONE
    parts = []
    for d in figures.drift:
        if d.sigma_deg_h is None:
            rate, sigma = fmt_sig(d.rate_deg_h, 3), ""
        else:
            rate = fmt_measured(d.rate_deg_h, d.sigma_deg_h, 3)
            sigma = f" ± {fmt_sigma(d.sigma_deg_h)}"
        who = f"{_e(d.instrument)}: " if d.instrument else ""
        caveats = "".join(f'<div class="why">⚠ {_e(c)}</div>' for c in d.caveats)
        parts.append(f"{who}{rate}{sigma} °/h{caveats}")
    return "<br>".join(parts)


def _dls(figures: WellFigures) -> str:
    """The largest DLS and, under it, the courses it is over."""
    if figures.max_dls is None:
        return _number(None, 2)
    courses = (
        f"courses ≥ {figures.dls_min_course:g} m" if figures.dls_min_course > 0 else "every course"
    )
    if figures.dls_rule == "report":
        rule = f"{courses}, as its report"
    elif figures.dls_rule == "default":
        rule = f"{courses} (no survey report: its default)"
    elif figures.dls_min_course > 0:  # read back from the tables of an earlier version's run
        rule = f"{courses} (the report's default: the run's own not recorded)"
    else:  # an earlier version's, in the ledger
        rule = courses
    return f'<td class="n">{fmt(figures.max_dls, 2)}<div class="why">{rule}</div></td>'


def _links(well_dir: Path, figures: WellFigures, page_dir: Path) -> str:
    links = []
    for name in figures.reports:
        target = _relative(well_dir / name, page_dir)
        label = Path(name).suffix.lstrip(".").upper()
        links.append(f'<a href="{_e(target)}">{label}</a>')
    return " ".join(links) or NONE


def _relative(path: Path, page_dir: Path) -> str:
    """A link from the page to ``path``: relative, percent-encoded."""
    try:
        relative = os.path.relpath(path, page_dir)
    except ValueError:  # another drive
        return path.resolve().as_uri()
    return urllib.parse.quote(Path(relative).as_posix())


def _number(value: float | None, decimals: int) -> str:
    return f'<td class="n">{NONE if value is None else fmt(value, decimals)}</td>'


def _about(fleet: Fleet, pipelines: list[str]) -> str:
    lines = []
    if pipelines:
        lines.append(f"Pipeline {_e(', '.join(pipelines))}")
    batches = fleet.batches
    if len(batches) == 1:
        b = batches[0]
        when = f"started {_when(b.started)}"
        ended = b.finished or fleet.ended
        if ended is not None:
            when += f", ended {_when(ended)} after {_duration(ended - b.started)}"
        lines.append(f"Batch {b.id} {when}")
    elif batches:
        last = batches[-1]
        lines.append(
            f"{len(batches)} batches, {_when(batches[0].started)} to "
            f"{_when(last.finished or last.heartbeat)}; latest batch {last.id} ({last.status})"
        )
    spent = sum(r.time_s for r in fleet.wells if r.time_s is not None)
    lines.append(f"Processing time of the wells listed: {_duration(spent)} in total")
    lines.append(f"Page written {_when(time.time())}")
    return "".join(f"<li>{line}</li>" for line in lines)


def _bar(tally: Counter[str]) -> str:
    shown = [(s, tally[s]) for s in (*ORDER, "not run") if tally[s]]
    label = ", ".join(f"{n} {WORDS[s][1].lower()}" for s, n in shown) or "no wells"
    segments = "".join(
        f'<span class="s-{s.replace(" ", "-")}" style="flex-grow:{n}"></span>' for s, n in shown
    )
    return f'<div class="bar" role="img" aria-label="{_e(label)}">{segments}</div>'


def _counts(tally: Counter[str]) -> str:
    statuses = [*COUNTED, *(s for s in ("running", "stale") if tally[s])]
    return "".join(
        f'<li class="s-{s.replace(" ", "-")}"><span class="sym" aria-hidden="true">'
        f"{WORDS[s][0]}</span> {WORDS[s][1]} <b>{tally[s]}</b></li>"
        for s in statuses
    )


def _rank(status: str) -> int:
    return ORDER.index(status) if status in ORDER else len(ORDER)


def _words(name: str) -> str:
    return name.replace("_", " ")


def _plural(n: int, noun: str) -> str:
    return f"{n} {noun}{'s' * (n != 1)}"


def _when(seconds: float) -> str:
    return dt.datetime.fromtimestamp(seconds, dt.UTC).strftime("%Y-%m-%d %H:%M UTC")


def _duration(seconds: float) -> str:
    seconds = max(0.0, seconds)
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, rest = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {rest} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes} min"


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
:root {{ --done:#009E73; --rejected:#E69F00; --failed:#D55E00; --interrupted:#CC79A7;
  --skipped:#56B4E9; --other:#CCCCCC; --ink:#1a1a1a; --soft:#555; --rule:#d9d9d9; }}
* {{ box-sizing: border-box; }}
body {{ font: 13px/1.35 system-ui, "Segoe UI", Roboto, "DejaVu Sans", Arial, sans-serif;
  color: var(--ink); margin: 20px 24px; }}
h1 {{ font-size: 20px; margin: 0 0 6px; }}
ul.about {{ list-style: none; padding: 0; margin: 0 0 12px; color: var(--soft); }}
ul.about li {{ display: inline; }}
ul.about li + li::before {{ content: " · "; }}
.bar {{ display: flex; height: 14px; border: 1px solid var(--ink); margin: 0 0 6px;
  max-width: 900px; }}
.bar span + span {{ border-left: 2px solid #fff; }}
ul.counts {{ list-style: none; padding: 0; margin: 0 0 16px; display: flex; flex-wrap: wrap;
  gap: 4px 18px; }}
ul.counts b {{ font-variant-numeric: tabular-nums; }}
table {{ border-collapse: collapse; width: 100%; }}
th, td {{ text-align: left; vertical-align: top; padding: 3px 8px;
  border-bottom: 1px solid var(--rule); white-space: nowrap; }}
td.st, td.problem {{ white-space: normal; min-width: 16em; }}
thead th {{ position: sticky; top: 0; background: #f2f2f2; border-bottom: 2px solid var(--ink);
  font-weight: 600; white-space: nowrap; }}
tbody th {{ font-weight: 600; white-space: nowrap; border-left: 6px solid var(--other); }}
.n {{ text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }}
.u {{ font-weight: 400; color: var(--soft); }}
.why {{ color: var(--soft); font-size: 12px; max-width: 42em; overflow-wrap: anywhere; }}
.problem {{ color: #8a3b00; }}
.sym {{ display: inline-block; width: 1.1em; text-align: center; }}
.ok {{ color: #007a5a; }} .bad {{ color: #b34700; font-weight: 700; }}
a {{ color: #0057a3; }}
.s-done {{ --c: var(--done); }} .s-rejected {{ --c: var(--rejected); }}
.s-failed {{ --c: var(--failed); }} .s-interrupted, .s-stale {{ --c: var(--interrupted); }}
.s-skipped {{ --c: var(--skipped); }} .s-running, .s-not-run {{ --c: var(--other); }}
.bar span {{ background: var(--c); }}
ul.counts .sym, tbody tr .sym {{ color: var(--c); font-weight: 700; }}
tbody tr th {{ border-left-color: var(--c); }}
tbody tr.s-failed, tbody tr.s-interrupted, tbody tr.s-stale {{ background: #fdf1ea; }}
tbody tr.s-rejected {{ background: #fdf7e6; }}
footer {{ margin-top: 14px; color: var(--soft); font-size: 12px; }}
@page {{ size: A4 landscape; margin: 10mm; }}
@media print {{
  body {{ margin: 0; font-size: 9px; }}
  h1 {{ font-size: 15px; }}
  .why {{ font-size: 8.5px; }}
  * {{ -webkit-print-color-adjust: exact; print-color-adjust: exact; }}
  thead th {{ position: static; }}
  tr {{ break-inside: avoid; }}
  a {{ color: inherit; text-decoration: none; }}
}}
</style>
</head>
<body>
<header>
<h1>{title}</h1>
<ul class="about">{about}</ul>
{bar}
<ul class="counts">{counts}</ul>
</header>
<main>
<table class="wells">
<thead><tr>{heads}</tr></thead>
<tbody>
{rows}
</tbody>
</table>
</main>
<footer>Failing wells first (failed, interrupted, rejected), then done and skipped wells;
by well within each. {none} the well has no such figure. SF: separation factor of the
reference well against its offset wells (the least, where the scan decides); DLS: dogleg
severity, the largest over the courses the well's survey report counts (those at least its
minimum course length long; a well without a survey report: the report's default), as told
under each; TD: the deepest station (TVD below the well's depth reference). Drift: the rate
a survey was corrected with or a calibration's, ± its σ.</footer>
</body>
</html>
""".replace("{none}", NONE)
