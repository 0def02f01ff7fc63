"""Figures for notebooks: the report's plan view and vertical section of a trajectory, as
drawings of the survey report's own charts. A drawing shows itself in Jupyter (SVG) and
``drawing.save('plan.svg')`` or ``drawing.save('plan.pdf')`` writes it as vector graphics."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pipeline.api.frames import TableLike, to_table

if TYPE_CHECKING:
    from pipeline.reports.charts.drawing import Drawing
    from pipeline.reports.plots import Path3

SIZE = (6.0, 5.0)
"""inches"""


def plot_plan(trajectory: TableLike) -> Drawing:
    """Plan view (north vs east, m, from the wellhead) of a trajectory, with the closure."""
    from pipeline.reports.charts.drawing import Drawing
    from pipeline.reports.plots import plan_view

    return Drawing(plan_view(SIZE, _path(trajectory)))


def plot_section(trajectory: TableLike, azimuth: float | None = None) -> Drawing:
    """Vertical section (m along ``azimuth``, deg, default: the table's own vertical-section
    plane) against TVD (m, down)."""
    from pipeline.reports.charts.drawing import Drawing
    from pipeline.reports.plots import vertical_section

    table = to_table(trajectory, what="trajectory")
    path = _path(table)
    if azimuth is None:
        vs = table.column("vertical_section").to_numpy()
    else:
        a = np.radians(azimuth)
        vs = path.north * np.cos(a) + path.east * np.sin(a)
    return Drawing(vertical_section(SIZE, vs, path, azimuth))


def _path(trajectory: TableLike) -> Path3:
    from pipeline.reports.plots import Path3
    from pipeline.reports.sections import north_label
    from pipeline.survey.stations import survey_offsets

    table = to_table(trajectory, what="trajectory")
    md, north, east, tvd = (table.column(c).to_numpy() for c in ("md", "north", "east", "tvd"))
    offsets = tuple(int(o) for o in survey_offsets(table))
    return Path3(md, north, east, tvd, offsets, north_label(table, "azi"))
