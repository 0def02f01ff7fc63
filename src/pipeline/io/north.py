"""The well's north reference is its azimuths': what a file names for its azimuth column
(a CSV ``# north_reference=`` line, a Parquet column's ``north_reference`` metadata) is
the well metadata's ``north_reference`` the reader returns, as LAS's NREF is."""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import warn_input
from pipeline.well import NorthReference, WellMetadata


def stated_north(
    path: Path, well: WellMetadata, stated: NorthReference | None, line: int = 0
) -> WellMetadata:
    """``well`` with ``stated`` (the north the file names for its azimuths; None: it names
    none) as its north reference; a well north reference naming another is overruled with
    a warning at ``line`` (the azimuths' own is what they are)."""
    if stated is None or well.north_reference == stated:
        return well
    if well.north_reference is not None:
        warn_input(
            path,
            f"well.north_reference {well.north_reference!r} contradicts the azimuths' "
            f"{stated} north: the azimuths' is the well's",
            line,
        )
    return well.merged({"north_reference": stated})
