"""Which stations of a store's trajectory are a survey's, by what WITSML 1.4.1.1 makes
their elements mean (the rules in :mod:`pipeline.io.witsml`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Literal

from pydantic import Field

from pipeline.errors import InputFileError
from pipeline.io.witsml.terms import STATION_STATUS

if TYPE_CHECKING:
    from pipeline.io.witsml.read import Node

StationsRead = Annotated[
    Literal["survey", "all"],
    Field(
        description="'survey' (default): leave out, with a warning at each one's line, the "
        "stations a store marks open (not validated) or rejected; 'all': read every station"
    ),
]
"""A reader option: which of a trajectory's stations are read."""
LEFT_OUT_STATUS = {
    "open": "not yet validated",
    "rejected": "its quality is not ok",
}
"""``statusTrajStation`` values whose stations the standard keeps out of the positions of
the stations below them, and what each says."""


def left_out(path: Path, station: Node) -> str | None:
    """Why ``station`` is not one of the survey's (None: it is): its ``statusTrajStation``.
    A value outside the schema's closed enumeration is refused at its line."""
    node = station.get("statusTrajStation")
    status = " ".join(node.text.split()) if node is not None else None
    if node is None or not status:
        return None
    if status not in STATION_STATUS:
        raise InputFileError(
            path,
            f"statusTrajStation {status!r}: expected one of {', '.join(sorted(STATION_STATUS))} "
            "(WITSML 1.4.1.1); a status this reader cannot read may mark a bad station",
            line=node.line,
            column="statusTrajStation",
        )
    if status in LEFT_OUT_STATUS:
        return (
            f"statusTrajStation {status!r} ({LEFT_OUT_STATUS[status]}: by the standard it "
            "enters no position of the stations below it)"
        )
    return None
