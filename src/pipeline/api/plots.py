"""Figures for notebooks: the report's plan view and vertical section of a trajectory, as
matplotlib figures (drawn by the same code as the survey report)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pipeline.api.frames import TableLike, to_table

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from pipeline.reports.plots import Path3

SIZE = (6.0, 5.0)
"""inches"""


def plot_plan(trajectory: TableLike) -> Figure:
    """Plan view (north vs east, m, from the wellhead) of a trajectory, with the closure."""
    from matplotlib.figure import Figure

    from pipeline.reports.plots import plan_view

    figure = Figure(figsize=SIZE)
    plan_view(figure, _path(trajectory))
    return figure


def plot_section(trajectory: TableLike, azimuth: float | None = None) -> Figure:
    """Vertical section (m along ``azimuth``, deg, default: the table's own vertical-section
    plane) against TVD (m, down)."""
    from matplotlib.figure import Figure

    from pipeline.reports.plots import vertical_section

    table = to_table(trajectory, what="trajectory")
    path = _path(table)
    if azimuth is None:
        vs = table.column("vertical_section").to_numpy()
    else:
        a = np.radians(azimuth)
        vs = path.north * np.cos(a) + path.east * np.sin(a)
    figure = Figure(figsize=SIZE)
    vertical_section(figure, vs, path, azimuth)
    return figure


def _path(trajectory: TableLike) -> Path3:
    from pipeline.reports.plots import Path3
    from pipeline.reports.sections import north_label
    from pipeline.survey.stations import survey_offsets

    table = to_table(trajectory, what="trajectory")
    md, north, east, tvd = (table.column(c).to_numpy() for c in ("md", "north", "east", "tvd"))
    offsets = tuple(int(o) for o in survey_offsets(table))
    return Path3(md, north, east, tvd, offsets, north_label(table, "azi"))
