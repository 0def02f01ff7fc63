"""Built-in WITSML plugin: survey trajectories as WITSML 1.4.1.1 ``trajectory`` documents
(writer ``witsml``) and back (reader ``witsml``, kind ``stations``).

Document (namespace ``http://www.witsml.org/schemas/1series``, ``version="1.4.1.1"``): one
``<trajectory uidWell uidWellbore uid>`` per survey of the table (its ``survey`` id is the
trajectory's name and uid), holding

* ``nameWell`` (``unnamed`` when the header names no well), ``nameWellbore`` (the well's
  ``wellbore``, else its name), ``name`` (the survey id, else ``survey <date>``);
  ``uidWell`` is the UWI (else the well name), ``uidWellbore`` the wellbore name, spaces
  as ``_``. Names and uids longer than WITSML's 64 characters are refused, never cut;
* ``dTimTrajStart`` — the survey date at 00:00 UTC (the header holds no time of day; left
  out for a survey of trajectories begun on several days, ``survey_date_last`` set: which
  began when is not known per trajectory, the extension values state the range);
  ``mdMn``/``mdMx``; ``serviceCompany``;
* ``magDeclUsed`` and ``gridCorUsed`` — the corrections applied to the azimuths, the
  well's ``declination_applied`` and ``grid_convergence_applied`` (recorded by the reader
  or by the ``north_reference`` stage when it applied them; left out when unknown: the
  site's ``declination`` and ``grid_convergence`` are extension values). Both positive
  east of true north, as WITSML defines them;
* ``aziVertSect`` with its origin at the wellhead, from the calculation record of the
  trajectory (:mod:`pipeline.survey.calculation`); ``aziRef`` from the azimuth column's
  north reference;
* per row a ``trajectoryStation``: ``typeTrajStation`` (the station's ``station_type``
  when it is a WITSML one, else ``tie in point`` for the first, else the station type of
  the tool), ``typeSurveyTool`` (from the station's ``tool_type``, else the well's
  free-text ``tool_type``: 'gyro north-seeking' → ``gyroscopic north seeking``…,
  ``unknown`` when it names no WITSML tool type), ``calcAlgorithm`` (when the trajectory
  records its method), ``md``, ``tvd``, ``incl``, ``azi``, ``dispNs``, ``dispEw``,
  ``vertSect``, ``dls``, ``rateTurn``, ``rateBuild`` for the columns present (uom ``m``,
  ``dega``, ``dega/30m``),
  and ``matrixCov`` (varianceNN … varianceVertVert, m², vertical down) from the ``cov_*``
  columns of a position-uncertainty trajectory;
* ``commonData``: a comment on the frames (and the error model of the covariances, when
  their columns state it, :mod:`pipeline.uncertainty.stated`; also as an
  ``extensionNameValue`` named ``gyropipe.error_model``), and every set well metadata field
  as an ``extensionNameValue`` named ``gyropipe.well.<field>`` so gyropipe reads the whole
  header back.

Numbers are written in shortest round-trip form, so they read back bit for bit; one that
is a null marker (``-999.25``…, which the reader takes for no value) is refused. Documents
validate against the WITSML 1.4.1.1 write schema (tested with the komle bindings of it).

The reader takes any WITSML 1.4.1.x ``trajectorys`` document (and a WITSML 2.0
``Trajectory``, read as its 1.4.1.1 tree: :mod:`pipeline.io.witsml.v2`): every trajectory
(or the one named by the option ``trajectory``) as stations in canonical units — md, inc,
azi required per station; tvd, north, east, dls kept when present (a ``tvd`` whose ``datum``
attribute names another datum than its ``md``'s, e.g. a TVDSS beside depths from the KB, is
left out with a warning: the trajectory gives no offset between them; the ``md`` of every
station must name one ``datum``, a wellDatum uid, or none, and one naming KB, DF, GL… the
depth reference the file states: else refused at the line); ``tool_type`` and
``station_type`` (``typeSurveyTool``, ``typeTrajStation``; ``unknown`` is none) — sorted by
MD, with a ``survey`` column (the names) when there are several and the ``source_line`` of
each station; ``uom`` converted (m, ft, ftUS; dega, rad; angle per length for DLS). A
trajectory's ``mdMn``/``mdMx`` (in their own uom, on the stations' datum) that leave a
station outside, or reach past the first or last station by more than 5 cm (stations
missing: a truncated export, a store's answer to a query for a depth range), are warned of
at the line, as is one that cannot be read (no uom, not a number). A null marker
(:mod:`pipeline.io.nulls`: ``-999.25``… in the element's own unit) is no value: a station
without md, incl or azi (azi may be missing only at vertical) is an error at its line, or
left out with a warning under the option ``null_stations: drop``. The north reference is
``aziRef`` (``unknown`` or absent: the option ``north_reference``, which a trajectory
without one needs beside others with one: it never takes theirs). Well metadata: the
gyropipe extension values, overridden by the standard elements (nameWell, nameWellbore,
serviceCompany, dTimTrajStart; magDeclUsed and gridCorUsed (or gridConUsed) as the
corrections *applied*, ``declination_applied`` and ``grid_convergence_applied`` — never the
site's: a gridCorUsed of 0 on true-north azimuths says no grid correction was applied; the
stations' ``corUsed`` stnMagDeclUsed / stnGridCorUsed must agree with them and with each
other, and every trajectory's with the first's (the metadata hold one value for all the
azimuths); a non-zero grid correction on true- or magnetic-north azimuths, or a declination
on magnetic ones, is refused as a contradiction), the survey date: the earliest
``dTimTrajStart``, the day the survey began, and of trajectories begun on several days the
latest as ``survey_date_last`` (downstream, a geomagnetic model is then evaluated at no one
date for all the stations: a conversion to or from magnetic north, or a tool model's field,
needs the declination or field given; reports state the range; on magnetic-north azimuths
with no declination stated, whose declination follows from the date, trajectories started on
different days, or one undated beside a dated one, are refused at the line: read one at a
time; of other azimuths, an undated one beside a dated one is warned of), and the tool: the
first station's ``typeSurveyTool`` naming one (a tie-in point names none). An element the
schema allows once in its parent (a station's ``md``, ``statusTrajStation``, a trajectory's
``commonData``…) given twice is refused at the second. Every problem is an
:class:`~pipeline.errors.InputFileError` naming the file and the element's line.

What a store says of its trajectories and stations decides which are a survey's (reader
option ``stations``: ``survey``, the default; ``all`` reads every trajectory and station as
it is). A trajectory whose ``commonData/itemState`` is ``plan`` (a well plan, often in the
same store) or ``model`` (a what-if) is refused at that line, as is a value outside the
schema's closed enumeration; ``actual``, ``unknown`` or none is a survey. A station is left
out, with a warning at its line naming its md and why (none left: refused), unless what it
states is a survey station's, in the closed enumerations of WITSML 1.4.1.1: its
``typeTrajStation`` a tool's measurement (``gyro north seeking``…), ``tie in point`` or
``unknown`` — not a marker (``casing MD``, ``formation TVD``…: a point at a named depth,
interpolated among the survey's stations), a target (``target center``…), the end of a
plan's section (``hold to MD``, ``buildrate to INCL``…) nor a value of no enumeration (a
vendor's ``projected to bit``, ``interpolated``, ``inclination only``…); its
``statusTrajStation`` ``position``, ``unknown`` or none — not ``rejected`` (quality not ok)
nor ``open`` (not yet validated), by the schema in no position of the stations below them,
nor 1.3.1's ``valid``…; its own ``itemState`` not ``plan`` or ``model``. So the stations the
reader passes on are measurements and their tie-in: no stage downstream reads
``station_type``, which is kept as the file names it. A station without an azimuth away from
vertical (an inclination-only shot) is never azimuth 0 (above). A station's ``rawData``
(raw sensor values), ``valid`` (field values computed for its QC) and ``corUsed`` (the
corrections applied, above) mark no station good or bad. Of the
trajectory's flags, ``finalTraj`` false (preliminary or intermediate) and ``objectGrowing``
true (the store was still adding stations: deeper ones may follow) are warned of at their
line; ``definitive`` (the store's one trajectory for the wellbore) and ``memory`` (from a
tool's memory, not real time) change nothing the stations say and are not read; a flag that
is no ``xs:boolean`` is refused. ``parentTrajectory`` (a sidetrack's survey tied into its
main bore's) is not followed: when the first station lists no tvd, dispNs and dispEw it is
warned of (that station lies where the parent's put it, which the survey stage's ``tie_…``
must give; a position listed there, the stage checks its tie against).
"""

from __future__ import annotations

from collections.abc import Callable

from pipeline.hookspecs import hookimpl
from pipeline.io.witsml.read import WitsmlOptions, read_witsml, sniff
from pipeline.io.witsml.write import write_witsml
from pipeline.registry import ReaderDef, WriterDef
from pipeline.tables import Stations

__all__ = ["WitsmlOptions", "read_witsml", "sniff", "write_witsml"]


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="witsml",
            description="survey stations from WITSML 1.4.1.x trajectory XML",
            kinds={"stations": Stations},
            read=read_witsml,
            sniff=sniff,
            options=WitsmlOptions,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="witsml",
            description="stations or trajectories as WITSML 1.4.1.1 trajectory XML (aziRef, "
            "declination and grid correction used, calcAlgorithm, covariance)",
            extension="xml",
            write=write_witsml,
        )
    )
