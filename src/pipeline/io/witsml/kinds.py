"""Which of a store's trajectories and stations are a survey's, by what WITSML 1.4.1.1
makes their elements mean (the rules in :mod:`pipeline.io.witsml`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field

from pipeline.errors import InputFileError, warn_input
from pipeline.io.witsml.terms import ITEM_STATES, STATION_STATUS

if TYPE_CHECKING:
    from pipeline.io.witsml.read import Node

StationsRead = Annotated[
    Literal["survey", "all"],
    Field(
        description="'survey' (default): refuse a trajectory a store marks a plan or a "
        "model, and leave out, with a warning at each one's line, the stations it marks "
        "open (not validated), rejected, planned or modelled; 'all': read every trajectory "
        "and station as it is"
    ),
]
"""A reader option: which trajectories and stations are read."""
LEFT_OUT_STATUS = {
    "open": "not yet validated",
    "rejected": "its quality is not ok",
}
"""``statusTrajStation`` values whose stations the standard keeps out of the positions of
the stations below them, and what each says."""
NOT_ACTUAL = {"plan": "a plan, to be drilled", "model": "a model, for what-if calculations"}
"""``commonData/itemState`` values of what is not a survey, and what each says."""
_BOOLEAN = {"true": True, "1": True, "false": False, "0": False}
"""``xs:boolean`` text."""


def check_trajectory(path: Path, traj: Node, stations: str) -> None:
    """Refuse (``stations: survey``) a trajectory whose ``commonData/itemState`` is ``plan``
    or ``model``; warn of one the store marks preliminary (``finalTraj`` false) or still
    growing (``objectGrowing`` true: stations deeper than its last may follow)."""
    state = _item_state(path, traj)
    if state is not None and state[0] in NOT_ACTUAL and stations == "survey":
        raise InputFileError(
            path,
            f"commonData/itemState {state[0]!r}: the trajectory is {NOT_ACTUAL[state[0]]}, "
            "not a survey; the reader option stations: all reads its stations",
            line=state[1].line,
            column="itemState",
        )
    final, growing = _flag(path, traj, "finalTraj"), _flag(path, traj, "objectGrowing")
    if final is not None and not final[0]:
        warn_input(
            path,
            f"finalTraj {final[1].text.strip()}: the store marks the trajectory preliminary or "
            "intermediate, not its final survey",
            final[1].line,
        )
    if growing is not None and growing[0]:
        warn_input(
            path,
            f"objectGrowing {growing[1].text.strip()}: the store was still adding stations "
            "to the trajectory (being drilled): stations deeper than its last may follow",
            growing[1].line,
        )


def check_tie_in(path: Path, traj: Node, first: dict[str, Any]) -> None:
    """Warn where a trajectory tied into another (``parentTrajectory``: a sidetrack's into
    its main bore's) lists no tvd, dispNs and dispEw at its first station (a row, m): the
    positions above it are the parent's, which the file does not hold."""
    parent = traj.get("parentTrajectory")
    if parent is None or all(first.get(k) is not None for k in ("tvd", "north", "east")):
        return
    reference = parent.get("trajectoryReference")
    name = " ".join(reference.text.split()) or reference.attrs.get("uidRef") if reference else ""
    warn_input(
        path,
        f"parentTrajectory {name!r}: the trajectory is tied into another, but its first "
        f"station, at md {first['md']!r} m (line {first['source_line']}), lists no tvd, dispNs "
        "and dispEw: it lies where the parent's stations put it, not below a vertical hole "
        "(give the survey stage its tie_tvd, tie_north and tie_east)",
        parent.line,
    )


def left_out(path: Path, station: Node) -> str | None:
    """Why ``station`` is not one of the survey's (None: it is): its ``statusTrajStation``
    or its own ``commonData/itemState``. A value outside the schema's closed enumeration is
    refused at its line."""
    node = station.get("statusTrajStation")
    status = " ".join(node.text.split()) if node is not None else ""
    if node is not None and status and status not in STATION_STATUS:
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
    state = _item_state(path, station)
    if state is not None and state[0] in NOT_ACTUAL:
        return f"commonData/itemState {state[0]!r} ({NOT_ACTUAL[state[0]]}, not a measurement)"
    return None


def _item_state(path: Path, holder: Node) -> tuple[str, Node] | None:
    """The ``commonData/itemState`` of a trajectory or station and its element (None: not
    stated); one outside the schema's closed enumeration is refused at its line."""
    common = holder.get("commonData")
    node = common.get("itemState") if common is not None else None
    state = " ".join(node.text.split()) if node is not None else ""
    if node is None or not state:
        return None
    if state not in ITEM_STATES:
        raise InputFileError(
            path,
            f"commonData/itemState {state!r}: expected one of {', '.join(sorted(ITEM_STATES))} "
            "(WITSML 1.4.1.1); this reader cannot tell whether it is a survey",
            line=node.line,
            column="itemState",
        )
    return state, node


def _flag(path: Path, holder: Node, name: str) -> tuple[bool, Node] | None:
    """A boolean element of ``holder`` (None: absent), refused at its line when not one."""
    node = holder.get(name)
    if node is None:
        return None
    text = node.text.strip()
    if text not in _BOOLEAN:
        raise InputFileError(
            path,
            f"{name} {text!r} is not a boolean (true, false, 1 or 0)",
            line=node.line,
            column=name,
        )
    return _BOOLEAN[text], node
