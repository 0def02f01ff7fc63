"""WITSML 2.0 ``Trajectory`` documents, read as the WITSML 1.4.1.1 tree of one trajectory.

WITSML 2.0 keeps 1.4.1.1's trajectory and station elements, capitalised
(``TrajectoryStation/Md`` for ``trajectoryStation/md``, with the same ``uom`` and ``datum``
attributes); what differs is translated here, so one reader holds every rule:

* one ``Trajectory`` per document (root, attribute ``schemaVersion`` 2.0), its name in
  ``eml:Citation/eml:Title``, its wellbore's in ``Wellbore/eml:Title``, its uid the ``uuid``;
* ``GrowingStatus`` ``active`` is 1.4.1.1's ``objectGrowing`` true, ``inactive`` or
  ``closed`` false;
* ``eml:ExtensionNameValue`` (gyropipe's well metadata among them) is 1.4.1.1's
  ``commonData/extensionNameValue``;
* ``TypeTrajStation`` names what defines a station, the tool is ``TypeSurveyTool``: a
  normal survey station, ``MD INCL and AZI``, is read as 1.4.1.1's station of its tool
  (``gyroscopic north seeking`` → ``gyro north seeking``; ``unknown`` without one), and
  ``MD and INCL`` (an inclination-only survey) and ``interpolated`` are left out as no
  measurement of a direction;
* ``ParentTrajectory`` (a reference) is ``parentTrajectory`` with its title.

WITSML 2.1, whose depths and depth range took another form, is refused with the versions
this reader reads."""

from __future__ import annotations

from pathlib import Path
from typing import Final

from pipeline.errors import InputFileError
from pipeline.io.witsml.terms import NS, SURVEY_TOOLS, VERSION
from pipeline.io.witsml.tree import Node

NS_2: Final = "http://www.energistics.org/energyml/data/witsmlv2"
NS_EML: Final = "http://www.energistics.org/energyml/data/commonv2"
MEASURED: Final = "MD INCL and AZI"
"""WITSML 2.0's ``TypeTrajStation`` of a normal MWD or gyro survey station."""
GROWING = {"active": "true", "inactive": "false", "closed": "false"}
"""``GrowingStatus`` → 1.4.1.1's ``objectGrowing``."""


def as_1series(path: Path, root: Node) -> Node:
    """The 1.4.1.1 ``trajectorys`` tree of a WITSML 2.0 ``Trajectory`` document's ``root``
    (lines kept: every problem is told at the file's own line)."""
    version = root.attrs.get("schemaVersion", "")
    if root.name != "Trajectory":
        raise InputFileError(
            path, f"root element <{root.name}> of WITSML 2: expected <Trajectory>", line=root.line
        )
    if version.split(".")[:2] != ["2", "0"]:
        raise InputFileError(
            path,
            f"schemaVersion {version!r}: this reader reads WITSML 2.0 Trajectory and WITSML "
            "1.4.1.x trajectorys documents",
            line=root.line,
        )
    trajectory = Node("trajectory", NS, {"uid": root.attrs.get("uuid", "")}, root.line)
    common = Node("commonData", NS, {}, root.line)
    for child in root.children:
        if child.name == "Citation" and child.namespace == NS_EML:
            _titled(trajectory, "name", child)
        elif child.name == "ExtensionNameValue" and child.namespace in (NS_EML, NS_2):
            common.children.append(_renamed(child))
        elif child.namespace != NS_2:
            continue
        elif child.name == "Wellbore":
            _titled(trajectory, "nameWellbore", child)
        elif child.name == "ParentTrajectory":
            parent = Node("parentTrajectory", NS, {}, child.line)
            _titled(parent, "trajectoryReference", child)
            trajectory.children.append(parent)
        elif child.name == "GrowingStatus":
            text = " ".join(child.text.split())
            growing = Node("objectGrowing", NS, {}, child.line, text=GROWING.get(text, text))
            trajectory.children.append(growing)
        elif child.name == "TrajectoryStation":
            trajectory.children.append(_station(child))
        else:
            trajectory.children.append(_renamed(child))
    if common.children:
        trajectory.children.append(common)
    return Node("trajectorys", NS, {"version": VERSION}, root.line, [trajectory])


def _renamed(node: Node) -> Node:
    """``node`` and its elements in 1.4.1.1's spelling (first letter lower case)."""
    return Node(
        node.name[:1].lower() + node.name[1:],
        NS,
        dict(node.attrs),
        node.line,
        [_renamed(c) for c in node.children],
        node.text,
    )


def _station(node: Node) -> Node:
    """A ``TrajectoryStation``; a normal survey station's type is its tool's station type."""
    station = _renamed(node)
    kind = station.get("typeTrajStation")
    if kind is not None and " ".join(kind.text.split()) == MEASURED:
        tool = station.text_of("typeSurveyTool")
        kind.text = SURVEY_TOOLS.get(tool or "unknown", SURVEY_TOOLS["unknown"])
    return station


def _titled(holder: Node, name: str, reference: Node) -> None:
    """Append to ``holder`` an element ``name`` holding ``reference``'s ``eml:Title``."""
    title = next((c for c in reference.children if c.name == "Title"), None)
    if title is not None and title.text.strip():
        holder.children.append(Node(name, NS, {}, title.line, text=title.text))
