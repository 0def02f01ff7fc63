"""Where a survey's positions start: its tie-on, the position of its first station.

A stations file that lists its own positions (TVD, north, east: a vendor's listing, a
WITSML trajectory's ``tvd``/``dispNs``/``dispEw``) gives its survey's tie-on at its first
station; the stages integrating stations start each survey there (:func:`listed_ties`)
unless the pipeline gives a tie of its own. Listed positions are read only in the table's
length unit (m) and in the north reference of its azimuths (NED from the wellhead);
anything else is refused (:func:`listed_positions`), never mixed in. Lengths in m.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.contracts import NORTH_KEY, SOURCE_KEY, SOURCE_LINE, UNIT_KEY
from pipeline.errors import InputFileError
from pipeline.survey.interpolate import interpolate_md

STATED = ("tvd", "north", "east")
"""the columns of a stations file's own positions (m, NED from the wellhead)"""
TieSource = Literal["stations file", "pipeline", "survey"]


class SurveyTie(BaseModel):
    """The position one survey's first station was tied at (m, NED from the wellhead, in
    the azimuths' north reference)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    survey: str | None = Field(None, description="survey id (None: the table's one survey)")
    md: float = Field(description="MD of the survey's first station, m")
    tvd: float = Field(description="its TVD, m")
    north: float = Field(description="its northing from the wellhead, m")
    east: float = Field(description="its easting from the wellhead, m")
    source: TieSource = Field(
        description="who gave it: the stations file's listing at that station, the pipeline "
        "(a stage's tie parameters or their defaults: TVD = MD, N = E = 0), or another "
        "survey of the table (``parent``) whose depths it begins within"
    )
    parent: str | None = Field(
        None,
        description="source 'survey': the survey it begins on (a sidetrack's main bore, the "
        "run it continues), its position there on that survey's minimum-curvature path",
    )

    def words(self) -> str:
        """The tie in words: ``Tied at MD 500.00 m, TVD 498.30 m, N 12.10 m, E -3.40 m (from
        the stations file)``, after ``survey 'name': `` where it names its survey."""
        named = f"survey {self.survey!r}: " if self.survey is not None else ""
        origin = (
            f"on survey {self.parent!r} at that MD" if self.source == "survey" else
            f"from the {self.source}"
        )  # fmt: skip
        return (
            f"{named}Tied at MD {self.md:.2f} m, TVD {self.tvd:.2f} m, N {self.north:.2f} m, "
            f"E {self.east:.2f} m ({origin})"
        )

    @property
    def position(self) -> np.ndarray:
        """TVD, north, east, m."""
        return np.array([self.tvd, self.north, self.east])


def ties_words(ties: tuple[SurveyTie, ...] | list[SurveyTie]) -> str:
    """Each survey's tie in words, joined by "; "."""
    return "; ".join(tie.words() for tie in ties)


def _where(stations: pa.Table, row: int) -> tuple[str, int]:
    """The file a table was read from and the line of ``row`` (0: not known); a table read
    from no file is "the stations table"."""
    source = (stations.schema.metadata or {}).get(SOURCE_KEY, b"").decode()
    if not source or SOURCE_LINE not in stations.column_names or stations.num_rows <= row:
        return source or "the stations table", 0
    return source, int(stations.column(SOURCE_LINE)[row].as_py() or 0)


def listed_positions(stations: pa.Table) -> np.ndarray | None:
    """The TVD, north and east a stations table lists, (n, 3) m (NaN where a cell is null);
    None when it lacks one of the three columns.

    Raises :class:`~pipeline.errors.InputFileError` (naming the file and the first station's
    line) for a column stating a unit other than m, or ``north``/``east`` stating a north
    reference other than the ``azi`` column's: a position in another north than the
    azimuths' would be mixed with positions integrated in theirs."""
    if not all(c in stations.column_names for c in STATED):
        return None
    azi_north = (stations.schema.field("azi").metadata or {}).get(NORTH_KEY)
    for name in STATED:
        meta = stations.schema.field(name).metadata or {}
        unit = meta.get(UNIT_KEY)
        if unit is not None and unit != b"m":
            path, line = _where(stations, 0)
            raise InputFileError(
                path,
                f"the listed {name} is in {unit.decode()!r}, not m: listed positions are read "
                "in the table's metres only (convert them when reading)",
                line,
                name,
            )
        north = meta.get(NORTH_KEY)
        if north is not None and name != "tvd" and north != azi_north:
            path, line = _where(stations, 0)
            azimuths = azi_north.decode() if azi_north is not None else "no stated"
            raise InputFileError(
                path,
                f"the listed {name} is referred to {north.decode()} north but the azimuths to "
                f"{azimuths} north: positions in another north than the azimuths' are not "
                "mixed with theirs (convert both to one north reference first)",
                line,
                name,
            )
    return np.column_stack(
        [stations.column(c).to_numpy(zero_copy_only=False).astype(float) for c in STATED]
    )


def listed_ties(stations: pa.Table, offsets: np.ndarray) -> list[np.ndarray | None]:
    """The TVD, north, east (m) a stations table lists at the first station of each survey
    (CSR ``offsets``), None for a survey whose first station lists not all three."""
    listed = listed_positions(stations)
    if listed is None:
        return [None] * (len(offsets) - 1)
    firsts = listed[offsets[:-1]]
    return [None if np.isnan(row).any() else row for row in firsts]


def chosen_tie(
    survey: str | None,
    md: float,
    listed: np.ndarray | None,
    given: tuple[float | None, float | None, float | None],
) -> SurveyTie:
    """A survey's tie at its first station (MD ``md``, m): the pipeline's where any of
    ``given`` (TVD, north, east, m) is set, the others at their fallbacks (TVD = MD,
    N = E = 0); else the file's ``listed`` TVD, north, east there; else the fallbacks."""
    if listed is not None and all(v is None for v in given):
        tvd, north, east = (float(v) for v in listed)
        return SurveyTie(
            survey=survey, md=md, tvd=tvd, north=north, east=east, source="stations file"
        )
    tvd_given, north_given, east_given = given
    return SurveyTie(
        survey=survey,
        md=md,
        tvd=md if tvd_given is None else tvd_given,
        north=north_given or 0.0,
        east=east_given or 0.0,
        source="pipeline",
    )


def tie_difference(tie: SurveyTie, listed: np.ndarray) -> float:
    """3-D distance (m) between an applied tie and the position a file lists there."""
    return float(np.linalg.norm(tie.position - listed))


def parent_of(md: np.ndarray, offsets: np.ndarray, k: int) -> int | None:
    """The survey (index into the CSR ``offsets``) survey ``k`` begins within: the first
    whose first MD is shallower than survey ``k``'s and whose last is not (None: none)."""
    lo = int(offsets[k])
    for j in range(len(offsets) - 1):
        a, b = int(offsets[j]), int(offsets[j + 1])
        if j != k and b > a and md[a] < md[lo] <= md[b - 1]:
            return j
    return None


def tie_to_parents(
    md: np.ndarray,
    inc: np.ndarray,
    azi: np.ndarray,
    offsets: np.ndarray,
    position: np.ndarray,
    ties: tuple[SurveyTie, ...],
) -> tuple[SurveyTie, ...]:
    """Re-tie each survey tied at the pipeline's fallback (TVD = MD, N = E = 0: its file
    lists no tie-on, the stage gives none) that begins within another survey's depths — a
    sidetrack listed beside its main bore, a run continuing another — at the other's
    position at that MD (on its minimum-curvature arc from the station above), shallowest
    first so that a parent is placed before its children. ``position`` ((n, 3) TVD, north,
    east, m, of stations at ``md`` m with ``inc``/``azi`` rad) is shifted in place;
    returns the ties applied."""
    names = [t.survey for t in ties]
    out = list(ties)
    for k in sorted(range(len(ties)), key=lambda i: float(md[offsets[i]])):
        lo, hi = int(offsets[k]), int(offsets[k + 1])
        parent = parent_of(md, offsets, k) if ties[k].source == "pipeline" else None
        if parent is None:
            continue
        a = int(offsets[parent])
        step = a + int(np.searchsorted(md[a : int(offsets[parent + 1])], md[lo], "right")) - 1
        step = min(step, int(offsets[parent + 1]) - 2)
        s = slice(step, step + 2)
        tvd0, north0, east0 = position[step]
        there = interpolate_md(md[s], inc[s], azi[s], md[lo], tie=(north0, east0, tvd0))
        at = np.array([there.tvd[0], there.north[0], there.east[0]])
        position[lo:hi] += at - position[lo]
        out[k] = SurveyTie(
            survey=names[k],
            md=float(md[lo]),
            tvd=float(at[0]),
            north=float(at[1]),
            east=float(at[2]),
            source="survey",
            parent=names[parent],
        )
    return tuple(out)
