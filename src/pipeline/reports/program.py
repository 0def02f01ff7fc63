"""The survey program of a definitive survey: which run (tool, error model, file) each
depth interval of the well comes from, and where each run is tied to the one above."""

from __future__ import annotations

from pathlib import PurePath

import numpy as np
import pyarrow as pa

from pipeline.reports.document import Column, Paragraph, Section, Table, fmt

PROVENANCE = ("run", "tool_model", "source", "section")
"""Columns of a definitive survey's per-station provenance."""


def program_section(trajectory: pa.Table) -> Section | None:
    """The survey program (None: the trajectory is not a definitive survey)."""
    if not all(c in trajectory.schema.names for c in PROVENANCE):
        return None
    section = trajectory.column("section").to_numpy()
    md = trajectory.column("md").to_numpy()
    starts = np.flatnonzero(np.r_[True, section[1:] != section[:-1]])
    ends = np.r_[starts[1:], section.size] - 1
    rows = []
    for a, b in zip(starts, ends, strict=True):
        source = str(trajectory.column("source")[a].as_py())
        rows.append(
            (
                str(int(section[a]) + 1),
                str(trajectory.column("run")[a].as_py()),
                str(trajectory.column("tool_model")[a].as_py()),
                f"{fmt(md[a])} – {fmt(md[b])}",
                str(b - a + 1),
                PurePath(source).name if source else "—",
            )
        )
    return Section(
        "Survey program",
        (
            Table(
                "Sections of the definitive survey",
                (
                    Column("Section"),
                    Column("Run", align="left"),
                    Column("Error model", align="left"),
                    Column("Stations listed", "m MD", align="left"),
                    Column("Stations"),
                    Column("File", align="left", wrap=True),
                ),
                tuple(rows),
                kind="program",
            ),
            Paragraph(
                "Each section below the first is tied at the last listed station of the "
                "section above. Position uncertainty is propagated over the listed stations, "
                "each with its own run's error model (see Method): a run's systematic errors "
                "are correlated within that run only, and nothing carried from above is lost "
                "at a tie."
            ),
        ),
        key="program",
    )
