"""Which of a store's trajectories and stations are a survey's, by what WITSML 1.4.1.1
makes their elements mean (the rules in :mod:`pipeline.io.witsml`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from pipeline.contracts import SOURCE_LINE
from pipeline.errors import InputFileError, warn_input
from pipeline.io.witsml.terms import (
    ITEM_STATES,
    MARKER_TYPES,
    NOT_MEASURED_2,
    PLAN_SECTION_TYPES,
    STATION_STATUS,
    SURVEY_STATION_TYPES,
    TARGET_TYPES,
)

if TYPE_CHECKING:
    from pipeline.io.witsml.tree import Node

LEFT_OUT_STATUS = {
    "open": "not yet validated",
    "rejected": "its quality is not ok",
}
"""``statusTrajStation`` values whose stations the standard keeps out of the positions of
the stations below them, and what each says."""
NOT_ACTUAL = {"plan": "a plan, to be drilled", "model": "a model, for what-if calculations"}
"""``commonData/itemState`` values of what is not a survey, and what each says."""
OUTSIDE = "none of WITSML 1.4.1.1's values"
_BOOLEAN = {"true": True, "1": True, "false": False, "0": False}
"""``xs:boolean`` text."""


def check_trajectory(path: Path, traj: Node, stations: str, others: list[str]) -> None:
    """Refuse (``stations: survey``) a trajectory whose ``commonData/itemState`` is ``plan``
    or ``model``, naming the ``others`` of the file (uids, else names) the option
    ``trajectory`` reads alone; warn of one the store marks preliminary (``finalTraj``
    false) or still growing (``objectGrowing`` true: stations deeper than its last may
    follow)."""
    state = _item_state(path, traj)
    if state is not None and state[0] in NOT_ACTUAL and stations == "survey":
        named = " or ".join(map(repr, others))
        alone = f"the option trajectory: {named} reads the file's other alone, " if others else ""
        raise InputFileError(
            path,
            f"commonData/itemState {state[0]!r}: the trajectory is {NOT_ACTUAL[state[0]]}, "
            f"not a survey; {alone}the reader option stations: all reads its stations",
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
    uid = reference.attrs.get("uidRef") if reference is not None else None
    name = parent.text_of("trajectoryReference") or uid
    named = repr(name) if name else "(naming no trajectory by text or uidRef)"
    warn_input(
        path,
        f"parentTrajectory {named}: the trajectory is tied into another, but its first "
        f"station, at md {first['md']!r} m (line {first[SOURCE_LINE]}), lists no tvd, dispNs "
        "and dispEw: it lies where the parent's stations put it, not below a vertical hole "
        "(give the survey stage its tie_tvd, tie_north and tie_east)",
        parent.line,
    )


def left_out(station: Node) -> str | None:
    """Why ``station`` is not one of the survey's (None: it is): its ``typeTrajStation``
    names no measurement, its ``statusTrajStation`` no validated one, or its own
    ``commonData/itemState`` no actual one — a value outside the schema's closed
    enumeration is none either."""
    kind = station.text_of("typeTrajStation")
    if kind is not None and kind not in SURVEY_STATION_TYPES:
        return f"typeTrajStation {kind!r} ({_not_measured(kind)})"
    status = station.text_of("statusTrajStation")
    if status in LEFT_OUT_STATUS:
        return (
            f"statusTrajStation {status!r} ({LEFT_OUT_STATUS[status]}: by the standard it "
            "enters no position of the stations below it)"
        )
    if status is not None and status not in STATION_STATUS:
        return f"statusTrajStation {status!r} ({OUTSIDE}: not taken for validated)"
    common = station.get("commonData")
    state = common.text_of("itemState") if common is not None else None
    if state in NOT_ACTUAL:
        return f"commonData/itemState {state!r} ({NOT_ACTUAL[state]}, not a measurement)"
    if state is not None and state not in ITEM_STATES:
        return f"commonData/itemState {state!r} ({OUTSIDE}: not taken for actual)"
    return None


def _not_measured(kind: str) -> str:
    """What a ``typeTrajStation`` value outside :data:`SURVEY_STATION_TYPES` names."""
    if kind in MARKER_TYPES:
        return "a point at a named depth, interpolated between the survey's stations"
    if kind in TARGET_TYPES:
        return "a target's position"
    if kind in PLAN_SECTION_TYPES:
        return "the end of a plan's section"
    if kind in NOT_MEASURED_2:
        return NOT_MEASURED_2[kind]
    return f"{OUTSIDE}: not taken for a measurement, as a projection or an interpolation is none"


def _item_state(path: Path, holder: Node) -> tuple[str, Node] | None:
    """The ``commonData/itemState`` of a trajectory and its element (None: not stated); one
    outside the schema's closed enumeration is refused at its line."""
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
