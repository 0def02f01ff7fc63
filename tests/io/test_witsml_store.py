"""What an operator's store says about its trajectories and stations, read for what the
WITSML 1.4.1.1 schema makes it mean (documents as a store returns them: namespace, uids,
elements in schema order, uoms, ``commonData``; each validated by the schema bindings):

* ``statusTrajStation`` ``rejected`` (quality not ok) and ``open`` (not yet validated):
  neither enters the positions of the stations below it, by the standard; left out with a
  warning at the station's line naming its MD and status (reader option ``stations: all``
  keeps them), as one of a value outside the closed enumeration;
* ``commonData/itemState`` ``plan`` or ``model``: a well plan or a what-if, not a survey —
  the trajectory refused unless ``stations: all`` asks for it, a station of an actual one
  left out; ``finalTraj`` false (preliminary) and ``objectGrowing`` true (still drilling)
  warned of; a sidetrack's ``parentTrajectory`` warned of when its tie-in lists no position;
* ``typeTrajStation``: a marker (casing, formation… at a named depth: interpolated), a
  target or a plan's section is no measurement, nor is a value outside the closed
  enumeration ('projected to bit'…): left out with a warning; an inclination-only shot
  (no azimuth) is never read as azimuth 0.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from komle.bindings.v1411.write import witsml as wml
from vendor_exports import survey_pipeline

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning
from pipeline.io.witsml.terms import (
    MARKER_TYPES,
    PLAN_SECTION_TYPES,
    SURVEY_STATION_TYPES,
    TARGET_TYPES,
)
from tests_support import gyropipe_cli

NS = "http://www.witsml.org/schemas/1series"
SURVEY = [(0.0, 0.0, 0.0), (300.0, 0.0, 0.0), (330.0, 1.5, 45.0), (360.0, 3.0, 45.0)]
"""md (m), incl, azi (deg) of a J-well's first stations: vertical to 300 m, then building."""
FIRST_STATION_LINE = 14
"""The line of the first ``trajectoryStation`` of :func:`store_document`."""


def station(
    k: int,
    md: float,
    inc: float,
    azi: float,
    *,
    kind: str | None = None,
    status: str | None = None,
    state: str | None = None,
    position: tuple[float, float, float] | None = None,
) -> str:
    """One ``trajectoryStation`` on one line, elements in schema order (uom m, dega):
    ``state`` its own ``commonData/itemState``, ``position`` its tvd, dispNs, dispEw (m)."""
    kind = kind or ("tie in point" if k == 0 else "gyro north seeking")
    tool = (
        ""
        if kind == "tie in point"
        else "<typeSurveyTool>gyroscopic north seeking</typeSurveyTool>"
    )
    status_element = f"<statusTrajStation>{status}</statusTrajStation>" if status else ""
    common = f"<commonData><itemState>{state}</itemState></commonData>" if state else ""
    tvd, placed = "", ""
    if position is not None:
        tvd = f'<tvd uom="m">{position[0]!r}</tvd>'
        placed = f'<dispNs uom="m">{position[1]!r}</dispNs><dispEw uom="m">{position[2]!r}</dispEw>'
    return (
        f'    <trajectoryStation uid="stn-{k:03d}">'
        f"<dTimStn>2026-03-02T{8 + k // 60:02d}:{k % 60:02d}:00Z</dTimStn>"
        f"<typeTrajStation>{kind}</typeTrajStation>{tool}"
        f'<md uom="m">{md!r}</md>{tvd}<incl uom="dega">{inc!r}</incl><azi uom="dega">{azi!r}</azi>'
        f"{placed}{status_element}{common}</trajectoryStation>"
    )


def store_document(
    stations: list[str],
    *,
    head: str = "",
    flags: str = "",
    state: str = "actual",
    md_min: float = 0.0,
) -> str:
    """A store's answer to a trajectory query: ``head`` goes between ``name`` and
    ``dTimTrajStart``, ``flags`` before ``aziRef`` (schema order), stations from
    :data:`FIRST_STATION_LINE`, one a line; ``state`` its ``commonData/itemState``, ``md_min``
    its ``mdMn`` (m)."""
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<trajectorys xmlns="{NS}" version="1.4.1.1">',
            '  <trajectory uidWell="W-58" uidWellbore="W-58-1" uid="TRJ-0007">',
            "    <nameWell>58/1-A1</nameWell>",
            "    <nameWellbore>58/1-A1</nameWellbore>",
            "    <name>Gyro survey 0-360 m</name>",
            f"    {head}",
            "    <dTimTrajStart>2026-03-02T08:00:00Z</dTimTrajStart>",
            f'    <mdMn uom="m">{md_min!r}</mdMn>',
            f'    <mdMx uom="m">{SURVEY[-1][0]!r}</mdMx>',
            "    <serviceCompany>North Gyro Services</serviceCompany>",
            '    <magDeclUsed uom="dega">0</magDeclUsed>',
            f"    {flags}<aziRef>true north</aziRef>",
            *stations,
            "    <commonData>",
            "      <sourceName>Store A</sourceName>",
            "      <dTimCreation>2026-03-02T12:00:00Z</dTimCreation>",
            f"      <itemState>{state}</itemState>",
            "    </commonData>",
            "  </trajectory>",
            "</trajectorys>",
            "",
        ]
    )


def put(tmp_path: Path, text: str) -> Path:
    """The document on disk, after checking that the WITSML 1.4.1.1 schema accepts it."""
    wml.CreateFromDocument(text.encode())
    path = tmp_path / "store.xml"
    path.write_text(text)
    return path


def surveyed(**marks: dict[str, str]) -> list[str]:
    """:data:`SURVEY`'s stations, station ``k`` given the keywords ``marks[f"s{k}"]``."""
    return [station(k, *row, **marks.get(f"s{k}", {})) for k, row in enumerate(SURVEY)]


def test_a_rejected_station_is_left_out_with_a_warning_at_its_line(tmp_path: Path):
    path = put(tmp_path, store_document(surveyed(s2={"status": "rejected"})))
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 300.0, 360.0]
    (warning,) = [w for w in caught if "left out" in str(w.message)]
    assert str(warning.message).startswith(
        f"{path}:{FIRST_STATION_LINE + 2}: station at md 330.0 m"
    )
    assert "statusTrajStation 'rejected'" in str(warning.message)
    kept = gp.read(path, kind="stations", stations="all")
    assert kept["md"].tolist() == [0.0, 300.0, 330.0, 360.0]


def test_an_open_station_is_not_validated_and_left_out(tmp_path: Path):
    path = put(tmp_path, store_document(surveyed(s3={"status": "open"})))
    with pytest.warns(InputFileWarning, match=r"md 360\.0 m left out: statusTrajStation 'open'"):
        assert gp.read(path, kind="stations")["md"].tolist() == [0.0, 300.0, 330.0]


def test_validated_and_unknown_stations_are_read_without_a_warning(tmp_path: Path):
    marks = {"s1": {"status": "position"}, "s2": {"status": "unknown"}}
    path = put(tmp_path, store_document(surveyed(**marks)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        assert gp.read(path, kind="stations")["md"].tolist() == [s[0] for s in SURVEY]


def test_a_status_outside_the_enumeration_is_not_taken_for_validated(tmp_path: Path):
    path = tmp_path / "store.xml"  # 'valid' is WITSML 1.3.1's: not in 1.4.1.1's schema
    path.write_text(store_document(surveyed(s2={"status": "valid"})))
    with pytest.warns(InputFileWarning, match="left out: statusTrajStation 'valid'") as caught:
        assert gp.read(path, kind="stations")["md"].tolist() == [0.0, 300.0, 360.0]
    assert str(caught[0].message).startswith(f"{path}:{FIRST_STATION_LINE + 2}: ")


def test_a_survey_of_rejected_stations_only_is_refused(tmp_path: Path):
    marks = {f"s{k}": {"status": "rejected"} for k in range(len(SURVEY))}
    path = put(tmp_path, store_document(surveyed(**marks)))
    with pytest.raises(InputFileError, match="no survey station: 4 left out") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == 3


def test_the_cli_leaves_a_rejected_station_out_of_the_survey(tmp_path: Path):
    path = put(tmp_path, store_document(surveyed(s2={"status": "rejected"})))
    out = tmp_path / "out"
    spec = survey_pipeline(tmp_path)
    result = gyropipe_cli("run", spec, "--input", f"stations={path}", "--out", out, check=True)
    assert f"{path}:{FIRST_STATION_LINE + 2}: station at md 330.0 m left out" in result.stderr
    listed = gp.read(out / "trajectory.csv", kind="stations")
    assert listed["md"].tolist() == [0.0, 300.0, 360.0]


def item_state_line(stations: list[str]) -> int:
    """The line of the trajectory's ``commonData/itemState`` in :func:`store_document`."""
    return FIRST_STATION_LINE + len(stations) + 3


@pytest.mark.parametrize("state", ["plan", "model"])
def test_a_plan_is_not_read_as_a_survey(tmp_path: Path, state: str):
    stations = surveyed()
    path = put(tmp_path, store_document(stations, state=state))
    with pytest.raises(InputFileError, match=f"itemState '{state}'") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == item_state_line(stations)
    assert "stations: all" in str(caught.value)
    plan = gp.read(path, kind="stations", stations="all")  # asked for: the plan's stations
    assert plan["md"].tolist() == [s[0] for s in SURVEY]


def test_a_plan_beside_the_survey_names_the_trajectory_to_read(tmp_path: Path):
    """A store's answer holding the survey and its plan: refused at the plan, naming the
    survey by the option ``trajectory`` (stations: all would read the plan's stations as a
    second survey)."""
    survey = store_document(surveyed())
    plan = store_document(surveyed(), state="plan").replace('uid="TRJ-0007"', 'uid="PLAN-3"')
    second = plan.split('version="1.4.1.1">\n', 1)[1]
    path = tmp_path / "store.xml"
    path.write_text(survey.replace("</trajectorys>\n", second))
    with pytest.raises(InputFileError, match="itemState 'plan'") as caught:
        gp.read(path, kind="stations")
    assert "the option trajectory: 'TRJ-0007' reads the file's other alone" in str(caught.value)
    assert gp.read(path, kind="stations", trajectory="TRJ-0007")["md"].tolist() == [
        s[0] for s in SURVEY
    ]


def test_the_cli_refuses_a_plan_given_as_the_survey(tmp_path: Path):
    stations = surveyed()
    path = put(tmp_path, store_document(stations, state="plan"))
    spec = survey_pipeline(tmp_path)
    result = gyropipe_cli("run", spec, "--input", f"stations={path}", "--out", tmp_path / "out")
    assert result.returncode != 0
    assert f"{path}:{item_state_line(stations)}" in result.output
    assert not (tmp_path / "out" / "trajectory.csv").exists()


@pytest.mark.parametrize("state", ["actual", "unknown"])
def test_an_actual_trajectory_is_a_survey(tmp_path: Path, state: str):
    path = put(tmp_path, store_document(surveyed(), state=state))
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        assert gp.read(path, kind="stations").shape[0] == len(SURVEY)


def test_a_planned_station_of_an_actual_trajectory_is_left_out(tmp_path: Path):
    path = put(tmp_path, store_document(surveyed(s3={"state": "plan"})))
    with pytest.warns(InputFileWarning, match=r"md 360\.0 m left out: commonData/itemState 'plan'"):
        assert gp.read(path, kind="stations")["md"].tolist() == [0.0, 300.0, 330.0]


def test_an_item_state_outside_the_enumeration_is_refused(tmp_path: Path):
    path = tmp_path / "store.xml"
    path.write_text(store_document(surveyed(), state="proposal"))
    with pytest.raises(InputFileError, match="itemState 'proposal'") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == item_state_line(surveyed())


def test_a_preliminary_or_growing_trajectory_is_warned_of(tmp_path: Path):
    text = store_document(
        surveyed(),
        head="<objectGrowing>true</objectGrowing>",
        flags="<definitive>false</definitive><memory>0</memory><finalTraj>0</finalTraj>",
    )
    with pytest.warns(InputFileWarning) as caught:
        gp.read(put(tmp_path, text), kind="stations")
    told = sorted(str(w.message).split(": ", 1)[1] for w in caught)
    assert len(told) == 2
    assert told[0].startswith("finalTraj 0: the store marks the trajectory preliminary")
    assert told[1].startswith("objectGrowing true: the store was still adding stations")
    final = store_document(
        surveyed(),
        head="<objectGrowing>false</objectGrowing>",
        flags="<definitive>1</definitive><memory>true</memory><finalTraj>true</finalTraj>",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        gp.read(put(tmp_path, final), kind="stations")


def test_a_flag_that_is_no_boolean_is_refused_at_its_line(tmp_path: Path):
    path = tmp_path / "store.xml"
    path.write_text(store_document(surveyed(), flags="<finalTraj>yes</finalTraj>"))
    with pytest.raises(InputFileError, match="finalTraj 'yes' is not a boolean") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == FIRST_STATION_LINE - 1


PARENT = (
    "<parentTrajectory><trajectoryReference uidRef='TRJ-0001'>Main bore survey"
    "</trajectoryReference><wellboreParent uidRef='W-58-0'>58/1-A1</wellboreParent>"
    "</parentTrajectory>"
)


def test_a_sidetrack_tied_in_without_a_position_is_warned_of(tmp_path: Path):
    # a sidetrack's survey from the kick-off at 300 m, tied into the main bore's
    below = [station(k, *SURVEY[k]) for k in range(2, len(SURVEY))]
    stations = [station(1, *SURVEY[1], kind="tie in point"), *below]
    path = put(tmp_path, store_document(stations, head=PARENT, md_min=300.0))
    with pytest.warns(InputFileWarning, match="parentTrajectory 'Main bore survey'") as caught:
        gp.read(path, kind="stations")
    assert str(caught[0].message).startswith(f"{path}:7: ")
    assert "tie_tvd" in str(caught[0].message)
    tie = station(1, *SURVEY[1], kind="tie in point", position=(299.5, 1.25, -0.5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        table = gp.read(
            put(tmp_path, store_document([tie, *below], head=PARENT, md_min=300.0)), kind="stations"
        )
    assert table["tvd"].iloc[0] == 299.5  # the survey stage checks its tie against this


def test_a_parent_trajectory_naming_none_is_warned_of_as_such(tmp_path: Path):
    """No text nor uidRef in its trajectoryReference: said so, not named 'None'."""
    stations = [station(1, *SURVEY[1], kind="tie in point"), station(2, *SURVEY[2])]
    head = "<parentTrajectory><trajectoryReference/></parentTrajectory>"
    path = tmp_path / "store.xml"
    path.write_text(store_document(stations, head=head, md_min=300.0))
    with pytest.warns(InputFileWarning) as caught:
        gp.read(path, kind="stations")
    (told,) = [str(w.message) for w in caught if "parentTrajectory" in str(w.message)]
    assert told.startswith(f"{path}:7: parentTrajectory (naming no trajectory by text or uidRef):")


def test_the_station_types_are_the_schemas_closed_enumeration():
    enumeration = {e.value() for e in wml.TrajStationType._CF_enumeration.items()}
    kinds = (SURVEY_STATION_TYPES, MARKER_TYPES, TARGET_TYPES, PLAN_SECTION_TYPES)
    assert set().union(*kinds) == enumeration
    assert sum(len(k) for k in kinds) == len(enumeration) == 50  # each value in one kind


def test_a_marker_between_the_stations_is_left_out(tmp_path: Path):
    # a casing point a store inserted among the survey's stations, interpolated at 345 m
    stations = surveyed()
    stations.insert(3, station(9, 345.0, 2.25, 45.0, kind="casing MD"))
    path = put(tmp_path, store_document(stations))
    with pytest.warns(InputFileWarning, match="md 345.0 m left out: typeTrajStation 'casing MD'"):
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 300.0, 330.0, 360.0]
    assert set(table["station_type"]) == {"tie in point", "gyro north seeking"}
    every = gp.read(path, kind="stations", stations="all")
    assert every["station_type"].tolist()[3] == "casing MD"


@pytest.mark.parametrize("kind", ["projected to bit", "projection to TD", "interpolated"])
def test_a_projection_below_the_last_survey_station_is_left_out(tmp_path: Path, kind: str):
    # a vendor's projection to the bit, 20 m below the deepest survey station, under a type
    # of its own (none of WITSML 1.4.1.1's)
    stations = [*surveyed(), station(4, 380.0, 4.5, 45.0, kind=kind)]
    path = tmp_path / "store.xml"
    path.write_text(store_document(stations).replace(">360.0</mdMx>", ">380.0</mdMx>"))
    with pytest.warns(InputFileWarning, match=f"md 380.0 m left out: typeTrajStation '{kind}'"):
        assert gp.read(path, kind="stations")["md"].max() == 360.0


def test_a_plan_without_an_item_state_is_no_survey_either(tmp_path: Path):
    plan = [
        station(0, 0.0, 0.0, 0.0),
        station(1, 300.0, 0.0, 0.0, kind="hold to MD"),
        station(2, 360.0, 3.0, 45.0, kind="buildrate to MD"),
        station(3, 420.0, 6.0, 45.0, kind="target center"),
    ]
    path = tmp_path / "store.xml"
    text = store_document(plan).replace("<itemState>actual</itemState>", "")
    path.write_text(text.replace(">360.0</mdMx>", ">420.0</mdMx>"))
    with pytest.warns(InputFileWarning) as caught:
        assert gp.read(path, kind="stations")["md"].tolist() == [0.0]  # the tie-in alone
    told = [str(w.message).split(": ", 2)[2] for w in caught]
    assert [t.split(" (")[0] for t in told] == [
        "typeTrajStation 'hold to MD'",
        "typeTrajStation 'buildrate to MD'",
        "typeTrajStation 'target center'",
    ]


def test_an_inclination_only_shot_is_never_azimuth_zero(tmp_path: Path):
    shot = station(2, 330.0, 1.5, 45.0).replace('<azi uom="dega">45.0</azi>', "")
    stations = surveyed()
    stations[2] = shot
    path = put(tmp_path, store_document(stations))
    with pytest.raises(InputFileError, match="trajectoryStation has no <azi>") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == FIRST_STATION_LINE + 2
    with pytest.warns(InputFileWarning):
        dropped = gp.read(path, kind="stations", null_stations="drop")
    assert 330.0 not in dropped["md"].tolist()
    named = stations.copy()  # a vendor's own type for it: no measurement of WITSML's
    named[2] = shot.replace("gyro north seeking", "inclination only")
    path.write_text(store_document(named))
    with pytest.warns(InputFileWarning, match="typeTrajStation 'inclination only'"):
        assert 330.0 not in gp.read(path, kind="stations")["md"].tolist()


@pytest.mark.parametrize(
    ("element", "second", "line"),
    [  # each the schema allows once: the second contradicts the first, never silently read
        ("statusTrajStation", "<statusTrajStation>rejected</statusTrajStation>", 16),
        ("typeTrajStation", "<typeTrajStation>casing MD</typeTrajStation>", 16),
        ("md", '<md uom="ft">330.0</md>', 16),
        ("finalTraj", "<finalTraj>false</finalTraj>", 13),
        ("itemState", "<itemState>plan</itemState>", 22),
    ],
)
def test_an_element_the_schema_allows_once_is_refused_twice(
    tmp_path: Path, element: str, second: str, line: int
):
    """Station 2's element (line 16), or the trajectory's: its flags (line 13), its
    commonData's itemState (line 22: an actual one, then a plan's)."""
    stations = surveyed(s2={"status": "position"})
    end = f"</{element}>"
    stations[2] = stations[2].replace(end, end + second, 1)
    text = store_document(stations, flags="<finalTraj>true</finalTraj>")
    if element in ("finalTraj", "itemState"):
        text = text.replace(end, end + ("\n      " if element == "itemState" else "") + second)
    path = tmp_path / "store.xml"
    path.write_text(text)
    with pytest.raises(InputFileError, match=f"<{element}> appears twice") as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == line


def test_many_stations_left_out_are_warned_of_ten_by_one_and_the_rest_in_one(tmp_path: Path):
    """A store's 30 rejected stations gave 30 warnings: ten at their lines, the rest in one
    counting them with their lines."""
    rejected = [
        station(k, 300.0 + k, 1.0, 45.0, status="rejected") for k in range(1, 31)
    ]  # fmt: skip
    stations = [station(0, 0.0, 0.0, 0.0), *rejected, station(31, 400.0, 3.0, 45.0)]
    path = put(tmp_path, store_document(stations))
    with pytest.warns(InputFileWarning) as caught:
        table = gp.read(path, kind="stations")
    assert table["md"].tolist() == [0.0, 400.0]
    told = [str(w.message) for w in caught if "left out" in str(w.message)]
    assert len(told) == 11
    assert told[0].startswith(f"{path}:{FIRST_STATION_LINE + 1}: station at md 301.0 m")
    first, last = FIRST_STATION_LINE + 11, FIRST_STATION_LINE + 30
    assert told[-1] == (
        f"{path}:{first}: 20 more stations left out likewise (lines {first} to {last})"
    )
