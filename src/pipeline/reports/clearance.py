"""The clearance section of the survey report: the separation rule, the minimum separation
factor per offset well, the separation factor against MD and a travelling-cylinder plot."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.anticollision.tables import rule_of
from pipeline.reports import plots
from pipeline.reports.charts import ticks
from pipeline.reports.charts.model import Axis, Chart, Line, Marker, Panel, Span, Text, grid
from pipeline.reports.document import Block, Column, Fields, Plot, Section, Table, Verdict, fmt
from pipeline.reports.listing import col
from pipeline.reports.literature import ERROR_MODEL, GYRO_ERROR_MODEL, SEPARATION_RULE, Citations
from pipeline.reports.numbers import fmt_inches
from pipeline.uncertainty.tieon import tie_on_of

FloatArray = NDArray[np.float64]
ErrorModel = Callable[[str], tuple[str, bool]]
"""A tool model's name → its title and whether it is a gyro model."""
LEVEL_WORDS = {"pass": "pass", "warn": "caution", "fail": "stop"}


@dataclass(frozen=True)
class OffsetCurve:
    """One offset well's rows: reference MD, SF, travelling-cylinder angle and distance."""

    name: str
    md: FloatArray
    sf: FloatArray
    toolface: FloatArray
    distance: FloatArray


def _curves(table: pa.Table) -> list[OffsetCurve]:
    names = np.array(table.column("offset").to_pylist(), dtype=object)
    md, sf, tf, dist = (col(table, c) for c in ("md", "sf", "toolface", "distance"))
    out = []
    for name in dict.fromkeys(names.tolist()):
        rows = names == name
        out.append(OffsetCurve(str(name), md[rows], sf[rows], tf[rows], dist[rows]))
    return out


def sf_chart(size: plots.Size, curves: list[OffsetCurve], stop: float, caution: float) -> Chart:
    """Separation factor against reference MD per offset well (log scale), the stop and
    caution limits shaded."""
    (box,) = grid(size, right=1.6)
    finite = np.concatenate([c.sf[np.isfinite(c.sf) & (c.sf > 0)] for c in curves])
    low = min(float(finite.min()) if finite.size else stop, stop) / 1.5
    high = max(float(finite.max()) if finite.size else caution, caution) * 1.5
    panel = Panel(
        box,
        Axis("Reference MD (m)"),
        Axis("Separation factor", scale="log", limits=(low, high)),
        legend="outside",
    )
    panel.add(
        Span(low, stop, "#f6d5d1", label=f"SF < {fmt(stop, 2)}: stop"),
        Span(stop, caution, "#fbe7c6", label=f"SF < {fmt(caution, 2)}: caution"),
    )
    for k, c in enumerate(curves):
        sf = np.where(c.sf > 0, c.sf, np.nan)
        panel.add(Line(c.md, sf, plots.series_colour(k), label=c.name))
    return Chart(size, [panel])


QUARTERS = ((0.0, "high side"), (90.0, "right"), (180.0, "low side"), (270.0, "left"))
"""Directions named on the travelling cylinder, degrees clockwise from the high side."""


def travelling_cylinder(size: plots.Size, curves: list[OffsetCurve], reach: float) -> Chart:
    """Closest approach of each offset well seen down the reference well: angle clockwise
    from the high side (up), radius the centre-to-centre distance, points within ``reach``;
    drawn as a polar grid (circles at nice radii, spokes every 30°)."""
    side = size[1] - 0.4  # a square panel: the legend right beside the circle
    (box,) = grid(size, left=0.3, right=size[0] - 0.3 - side, top=0.2, bottom=0.2)
    edge = 1.25 * reach
    panel = Panel(
        box, Axis(limits=(-edge, edge)), Axis(limits=(-edge, edge)), frame=False, equal=True
    )
    turn = np.radians(np.linspace(0.0, 360.0, 145))
    radii, step = ticks.linear_ticks(0.0, reach, 5)
    for r in radii[1:]:
        if r < reach * 0.999:
            panel.add(Line(r * np.sin(turn), r * np.cos(turn), "#e1e6ec", 0.5))
    panel.add(Line(reach * np.sin(turn), reach * np.cos(turn), "#9aa5b1", 0.8))
    for angle in np.radians(np.arange(0.0, 360.0, 30.0)):
        spoke = np.array([0.0, reach])
        panel.add(Line(spoke * np.sin(angle), spoke * np.cos(angle), "#e1e6ec", 0.5))
    for r in radii[1:]:
        if r < reach * 0.999:
            label = f"{ticks.label(r, step)} m"
            panel.add(
                Text(
                    r * np.sin(np.radians(22.5)),
                    r * np.cos(np.radians(22.5)),
                    label,
                    size=6.5,
                    colour="#52606d",
                    dx=2,
                )
            )
    for degrees, name in QUARTERS:
        a = np.radians(degrees)
        panel.add(
            Text(
                reach * np.sin(a),
                reach * np.cos(a),
                name,
                size=7,
                colour="#52606d",
                dx=8 * np.sin(a),
                dy=8 * np.cos(a),
                ha="center" if degrees % 180 == 0 else ("left" if degrees == 90 else "right"),
                va="center" if degrees % 180 else ("bottom" if degrees == 0 else "top"),
            )
        )
    near_md = np.concatenate([c.md[c.distance <= reach] for c in curves])
    step = ticks.linear_ticks(*_span(near_md), MD_LABELS)[1] if near_md.size else 0.0
    placed: list[tuple[float, float]] = []  # labels drawn: another this close is left out
    for k, c in enumerate(curves):
        near = c.distance <= reach
        if near.any():
            a = np.radians(c.toolface[near])
            east, north = c.distance[near] * np.sin(a), c.distance[near] * np.cos(a)
            colour = plots.series_colour(k)
            panel.add(Line(east, north, colour, 0, marker=Marker("o", 2.6), label=c.name))
            for i in md_label_points(c.md[near], step):
                if any(np.hypot(east[i] - x, north[i] - y) < LABEL_GAP * reach for x, y in placed):
                    continue
                placed.append((float(east[i]), float(north[i])))
                text = f"MD {ticks.label(float(c.md[near][i]), step)}"
                panel.add(Text(east[i], north[i], text, size=5.5, colour=colour, dx=3, dy=2))
    panel.legend = "outside"
    return Chart(size, [panel])


MD_LABELS = 6
"""About this many MD steps label the travelling cylinder's traces."""
LABEL_GAP = 0.15
"""Nearest two MD labels of the travelling cylinder may be, in units of its reach."""


def _span(md: FloatArray) -> tuple[float, float]:
    return float(md.min()), float(md.max())


def md_label_points(md: FloatArray, step: float) -> list[int]:
    """Indices of a trace's points to label with their reference MD: the first point at or
    past each multiple of ``step`` (m) the trace's MDs reach (its first point when it
    spans none)."""
    if not md.size or step <= 0:
        return []
    order = np.argsort(md, kind="stable")
    marks = np.arange(np.ceil(md.min() / step), np.floor(md.max() / step) + 1) * step
    first = np.searchsorted(md[order], marks - 1e-9 * step)
    picked = dict.fromkeys(int(order[i]) for i in first if i < len(md))
    return list(picked) or [int(order[0])]


def wells_table(rule: Mapping[str, Any], titles: Mapping[str, str]) -> Table:
    """The wells the scan rests on: the reference well, then each offset well's slot (from
    the reference wellhead, in the reference's north), the tie-on its stations file lists,
    first-station TVD, hole and model."""
    tie = rule.get("reference_tie") or {}
    reference = {
        "model": rule.get("reference_model"),
        "hole_diameter": rule.get("reference_hole_diameter"),
        "north": 0.0,
        "east": 0.0,
        **({"tie_on": tie} if tie.get("source") == "stations file" else {}),
    }
    assumed = {  # offsets whose grid azimuths took the reference's convergence
        name: well["reference_convergence"]
        for name, well in rule.get("wells", {}).items()
        if well.get("reference_convergence") is not None
    }
    rows = []
    for name, well in {"Reference well": reference, **rule.get("wells", {})}.items():
        hole, model, tie = well.get("hole_diameter"), str(well.get("model")), well.get("tie_on")
        tvd = well["tvd"] if well.get("tvd") is not None else (tie or {}).get("tvd")
        rows.append(
            (
                name,
                fmt(well.get("north")),
                fmt(well.get("east")),
                f"TVD {fmt(tie['tvd'])}, N {fmt(tie['north'])}, E {fmt(tie['east'])}"
                if tie
                else "none listed",
                fmt(tvd) if tvd is not None else "its first MD",
                fmt_inches(hole),
                fmt(hole, 4),
                titles.get(model, model),
            )
        )
    return Table(
        "Wells scanned",
        (
            Column("Well", align="left"),
            Column("Slot north", "m"),
            Column("Slot east", "m"),
            Column("Tie-on its file lists", "m", align="left"),
            Column("First-station TVD", "m below the reference datum"),
            Column("Hole diameter", "in"),
            Column("Hole diameter", "m"),
            Column("Tool model", align="left"),
        ),
        tuple(rows),
        kind="clearance-wells",
        note="Slot: the well's position from the reference wellhead, in the north of the "
        "reference's azimuths; its first station lies there plus the north and east of the "
        "tie-on its stations file lists (from its own wellhead, turned to that north), where "
        "it lists one."
        + (
            f" {', '.join(assumed)}: grid azimuths stating no grid convergence of their own; "
            f"the reference well's ({next(iter(assumed.values()))}°) applied, the same grid "
            "assumed."
            if assumed
            else ""
        ),
    )


def _tie_on_fields(table: pa.Table) -> list[tuple[str, str]]:
    """The wells whose σ starts at a tie-on below MD 0 taken as exact, in words (none: [])."""
    record = tie_on_of(table)
    missing = [t for t in (record.surveys if record else ()) if t.missing()]
    if not missing:
        return []
    listed = ", ".join(f"{t.survey} from {fmt(t.md)} m MD" for t in missing)
    return [
        (
            "Tie-on uncertainty",
            f"{listed}: the survey starts at a tie-on taken as exactly known; the uncertainty "
            "of the hole above it is not included, so the separation factors against it are "
            "optimistic.",
        )
    ]


def clearance_section(table: pa.Table, citations: Citations, error_model: ErrorModel) -> Section:
    """The clearance section of a clearance table (one block per offset well); its tool
    models titled (and the gyro paper cited for a gyro model) by ``error_model``."""
    rule = rule_of(table)
    stop, caution = float(rule.get("stop", 1.0)), float(rule.get("caution", 1.5))
    curves = _curves(table)
    levels = table.column("level").to_pylist()
    offset_md, names = col(table, "offset_md"), table.column("offset").to_pylist()
    wells = rule.get("wells", {})
    between = col(table, "sf_between") if "sf_between" in table.schema.names else col(table, "sf")
    md_between = (
        col(table, "md_between") if "md_between" in table.schema.names else col(table, "md")
    )
    on_course = rule.get("level_on", "course") == "course"
    rows, marked = [], set()
    worst: tuple[float, str, float] | None = None
    for k, c in enumerate(curves):
        rows_of = [i for i, n in enumerate(names) if n == c.name]
        sf = np.where(np.isnan(c.sf), -np.inf, c.sf)
        i = int(np.argmin(sf))
        least = np.where(np.isnan(between[rows_of]), -np.inf, between[rows_of])
        j = int(np.argmin(least))
        level = max((levels[r] for r in rows_of), key=("pass", "warn", "fail").index)
        own = wells.get(c.name, {})
        rows.append(
            (
                c.name,
                str(own.get("model", "")),
                fmt_inches(own.get("hole_diameter")),
                fmt(c.sf[i], 2)
                if np.isfinite(c.sf[i])
                else "undefined (outside the model's range)",
                fmt(c.md[i]),
                fmt(offset_md[rows_of[i]]),
                fmt(c.distance[i], 2),
                fmt(least[j], 2) if np.isfinite(least[j]) else "undefined",
                fmt(md_between[rows_of[j]], 2),
                LEVEL_WORDS[level],
            )
        )
        if level == "fail":
            marked.add(k)
        decided = (
            (float(least[j]), float(md_between[rows_of[j]]))
            if on_course
            else (
                float(sf[i]),
                float(c.md[i]),
            )
        )
        if worst is None or decided[0] < worst[0]:
            worst = (decided[0], c.name, decided[1])
    assert worst is not None
    verdict = _verdict(worst, stop, caution, len(curves))
    models = {
        str(rule.get("reference_model", "")),
        *(str(w.get("model", "")) for w in wells.values()),
    }
    known = {m: error_model(m) for m in models if m}
    titles = {m: title for m, (title, _) in known.items()}
    gyro = any(is_gyro for _, is_gyro in known.values())
    fields = [
        ("Separation rule", f"ISCWSA separation factor {citations.cite(SEPARATION_RULE)}"),
        ("Position uncertainty", _uncertainty_words(citations, gyro)),
        ("Scaling factor k", fmt(rule.get("k", 3.5), 2)),
        ("Project-ahead σ", f"{fmt(rule.get('sigma_pa', 0.5), 2)} m"),
        ("Surface margin", f"{fmt(rule.get('surface_margin', 0.3), 2)} m"),
        ("Limits", f"stop below SF {fmt(stop, 2)}, caution below {fmt(caution, 2)}"),
        (
            "Level decided on",
            "the least SF along each reference course, between stations included"
            if on_course
            else "the SF at each reference station (between stations reported, not judged)",
        ),
        ("Conventions", _convention_words(rule)),
        *_common_sections(wells, str(rule.get("sidetrack", "zeroed"))),
        *_tie_on_fields(table),
    ]
    if "reference_model" in rule:
        hole = float(rule["reference_hole_diameter"])
        fields.append(
            (
                "Reference well",
                f"{rule['reference_model']}, hole {fmt_inches(hole)} in ({fmt(hole, 4)} m)",
            )
        )
    reach = max(4.0 * float(np.nanmin(col(table, "distance")) or 1.0), 10.0)
    reach = min(reach, float(np.nanmax(col(table, "distance"))))
    files = tuple(
        (name, f"{Path(w['source']).name} · sha256 {w['sha256']}")
        for name, w in wells.items()
        if "source" in w and "sha256" in w
    )
    blocks: list[Block] = [
        verdict,
        Fields("Rule and models", tuple(fields)),
        wells_table(rule, titles),
        *([Fields("Offset well surveys", files)] if files else []),
        Table(
            "Minimum separation factor per offset well",
            (
                Column("Offset well", align="left"),
                Column("Tool model", align="left"),
                Column("Hole", "in"),
                Column("Minimum SF"),
                Column("Reference MD", "m"),
                Column("Offset MD", "m"),
                Column("Centre distance", "m"),
                Column("Least SF between stations"),
                Column("at reference MD", "m"),
                Column("Level", align="left"),
            ),
            tuple(rows),
            kind="clearance",
            marked=frozenset(marked),
        ),
        Plot(
            "sf",
            "Separation factor against MD",
            "Separation factor at each reference station against the closest point of each "
            "offset well (logarithmic scale); shaded: the stop and caution limits.",
            partial(sf_chart, curves=curves, stop=stop, caution=caution),
            (6.9, 3.6),
        ),
        Plot(
            "cylinder",
            "Travelling cylinder",
            "Closest approach of each offset well seen down the reference well: direction "
            "from the reference's high side (clockwise), distance centre to centre, within "
            f"{fmt(reach, 0)} m; labels: the reference MD (m) of the station so marked.",
            partial(travelling_cylinder, curves=curves, reach=reach),
            (6.9, 4.2),
        ),
    ]
    return Section("Clearance", tuple(blocks), key="clearance")


def _convention_words(rule: Mapping[str, Any]) -> str:
    """The covariance conventions the scan applied (the ISCWSA clearance set's by default)."""
    first = (
        "each survey's first station exact (zero covariance)"
        if rule.get("first_station_exact", True)
        else "the surface tie-on's σ at each survey's first station"
    )
    vertical = (
        "vertical stations at azimuth 0° in the error models"
        if rule.get("vertical_azimuth", "north") == "north"
        else "vertical stations at their listed azimuth in the error models"
    )
    return f"{first}; {vertical}"


def _common_sections(wells: Mapping[str, Any], method: str) -> list[tuple[str, str]]:
    """A field per offset well that shares the reference's hole above a common point."""
    rule = (
        "the exact relative error: the trunk's errors cancelling, each run's terms "
        "independent (sidetrack: shared)"
        if method == "shared"
        else "both wells' uncertainty zeroed at the common point and independent below (the "
        "ISCWSA clearance set's rule)"
    )
    out = []
    for name, well in wells.items():
        kick = well.get("kickoff")
        if kick:
            how = (
                "named"
                if kick["how"] == "named"
                else "detected: its first stations on the reference path"
            )
            out.append(
                (
                    f"Common section: {name}",
                    f"kick-off at reference MD {fmt(kick['reference_md'], 2)} m ({how}); scanned "
                    f"from there, {rule}",
                )
            )
    return out


def _uncertainty_words(citations: Citations, gyro: bool) -> str:
    """The error models' papers, the gyro model's where a well is surveyed by a gyro."""
    words = f"ISCWSA error models {citations.cite(ERROR_MODEL)}"
    return f"{words} with the gyro terms of {citations.cite(GYRO_ERROR_MODEL)}" if gyro else words


def _verdict(worst: tuple[float, str, float], stop: float, caution: float, n: int) -> Verdict:
    sf, name, md = worst
    shown = "undefined (the centres meet)" if sf == -np.inf else fmt(sf, 2)
    where = f"minimum separation factor {shown} against {name} at {fmt(md)} m MD"
    if sf < stop:
        return Verdict("fail", f"Clearance: stop — {where} (below {fmt(stop, 2)}).")
    if sf < caution:
        return Verdict("warn", f"Clearance: caution — {where} (below {fmt(caution, 2)}).")
    return Verdict("ok", f"Clearance: {n} offset well(s) pass — {where}.")
