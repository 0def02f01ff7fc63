"""The clearance section of the survey report: the separation rule, the minimum separation
factor per offset well, the separation factor against MD and a travelling-cylinder plot."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.anticollision.tables import rule_of
from pipeline.reports import plots
from pipeline.reports.document import Block, Column, Fields, Plot, Section, Table, Verdict, fmt
from pipeline.reports.listing import col
from pipeline.reports.literature import ERROR_MODEL, SEPARATION_RULE, Citations

FloatArray = NDArray[np.float64]
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


def sf_chart(fig: plots.Canvas, curves: list[OffsetCurve], stop: float, caution: float) -> None:
    """Separation factor against reference MD per offset well (log scale), the stop and
    caution limits shaded."""
    (ax,) = plots.axes_grid(fig, right=1.6)
    finite = np.concatenate([c.sf[np.isfinite(c.sf) & (c.sf > 0)] for c in curves])
    low = min(float(finite.min()) if finite.size else stop, stop) / 1.5
    high = max(float(finite.max()) if finite.size else caution, caution) * 1.5
    ax.axhspan(low, stop, color="#f6d5d1", zorder=0, label=f"SF < {fmt(stop, 2)}: stop")
    ax.axhspan(stop, caution, color="#fbe7c6", zorder=0, label=f"SF < {fmt(caution, 2)}: caution")
    for k, c in enumerate(curves):
        colour = plots.SERIES_COLOURS[k % len(plots.SERIES_COLOURS)]
        ax.plot(c.md, np.where(c.sf > 0, c.sf, np.nan), color=colour, label=c.name)
    ax.set_yscale("log")
    ax.set_ylim(low, high)
    ax.set_xlabel("Reference MD (m)")
    ax.set_ylabel("Separation factor")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))


def travelling_cylinder(fig: plots.Canvas, curves: list[OffsetCurve], reach: float) -> None:
    """Closest approach of each offset well seen down the reference well: angle clockwise
    from the high side (up), radius the centre-to-centre distance, points within ``reach``."""
    ax: Any = fig.add_axes((0.1, 0.08, 0.62, 0.84), projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    for k, c in enumerate(curves):
        near = c.distance <= reach
        if not near.any():
            continue
        colour = plots.SERIES_COLOURS[k % len(plots.SERIES_COLOURS)]
        ax.plot(
            np.radians(c.toolface[near]),
            c.distance[near],
            color=colour,
            marker="o",
            markersize=2.2,
            linestyle="none",
            label=c.name,
        )
    ax.set_ylim(0.0, reach)
    ax.set_xticks(np.radians([0, 90, 180, 270]), ["high side", "right", "low side", "left"])
    ax.tick_params(labelsize=7)
    ax.legend(loc="upper left", bbox_to_anchor=(1.08, 1.0))


def clearance_section(table: pa.Table, citations: Citations) -> Section:
    """The clearance section of a clearance table (one block per offset well)."""
    rule = rule_of(table)
    stop, caution = float(rule.get("stop", 1.0)), float(rule.get("caution", 1.5))
    curves = _curves(table)
    levels = table.column("level").to_pylist()
    offset_md, names = col(table, "offset_md"), table.column("offset").to_pylist()
    wells = rule.get("wells", {})
    rows, marked = [], set()
    worst: tuple[float, str, float] | None = None
    for k, c in enumerate(curves):
        rows_of = [i for i, n in enumerate(names) if n == c.name]
        sf = np.where(np.isnan(c.sf), -np.inf, c.sf)
        i = int(np.argmin(sf))
        level = levels[rows_of[i]]
        own = wells.get(c.name, {})
        rows.append(
            (
                c.name,
                str(own.get("model", "")),
                fmt(own["hole_diameter"], 4) if "hole_diameter" in own else "",
                fmt(c.sf[i], 2) if np.isfinite(c.sf[i]) else "undefined (centres meet)",
                fmt(c.md[i]),
                fmt(offset_md[rows_of[i]]),
                fmt(c.distance[i], 2),
                LEVEL_WORDS[level],
            )
        )
        if level == "fail":
            marked.add(k)
        if worst is None or sf[i] < worst[0]:
            worst = (float(sf[i]), c.name, float(c.md[i]))
    assert worst is not None
    verdict = _verdict(worst, stop, caution, len(curves))
    fields = [
        ("Separation rule", f"ISCWSA separation factor {citations.cite(SEPARATION_RULE)}"),
        ("Position uncertainty", f"ISCWSA error models {citations.cite(ERROR_MODEL)}"),
        ("Scaling factor k", fmt(rule.get("k", 3.5), 2)),
        ("Project-ahead σ", f"{fmt(rule.get('sigma_pa', 0.5), 2)} m"),
        ("Surface margin", f"{fmt(rule.get('surface_margin', 0.3), 2)} m"),
        ("Limits", f"stop below SF {fmt(stop, 2)}, caution below {fmt(caution, 2)}"),
    ]
    if "reference_model" in rule:
        fields.append(
            (
                "Reference well",
                f"{rule['reference_model']}, hole {fmt(rule['reference_hole_diameter'], 4)} m",
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
        *([Fields("Offset well surveys", files)] if files else []),
        Table(
            "Minimum separation factor per offset well",
            (
                Column("Offset well", align="left"),
                Column("Tool model", align="left"),
                Column("Hole", "m"),
                Column("Minimum SF"),
                Column("Reference MD", "m"),
                Column("Offset MD", "m"),
                Column("Centre distance", "m"),
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
            f"{fmt(reach, 0)} m.",
            partial(travelling_cylinder, curves=curves, reach=reach),
            (6.9, 4.2),
        ),
    ]
    return Section("Clearance", tuple(blocks), key="clearance")


def _verdict(worst: tuple[float, str, float], stop: float, caution: float, n: int) -> Verdict:
    sf, name, md = worst
    shown = "undefined (the centres meet)" if sf == -np.inf else fmt(sf, 2)
    where = f"minimum separation factor {shown} against {name} at {fmt(md)} m MD"
    if sf < stop:
        return Verdict("fail", f"Clearance: stop — {where} (below {fmt(stop, 2)}).")
    if sf < caution:
        return Verdict("warn", f"Clearance: caution — {where} (below {fmt(caution, 2)}).")
    return Verdict("ok", f"Clearance: {n} offset well(s) pass — {where}.")
