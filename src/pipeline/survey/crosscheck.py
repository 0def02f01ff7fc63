"""The cross-check a survey engineer does by hand: the positions a stations file lists (a
vendor's TVD, north, east) against the positions recomputed from its MD, inclination and
azimuth, carried in the trajectory's Arrow schema metadata so the run, the report and the
exports can state it.

A station agrees when the 3-D distance between the two positions is at most
``tolerance + relative · (MD − MD of the survey's first station)``: a vendor's listing is
rounded (positions to 0.01 m or 0.1 ft, angles to 0.01°, i.e. up to 0.087 m per km of
along-hole distance), so the allowance grows with the distance surveyed. Lengths in m.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.survey.calculation import record_of, with_record
from pipeline.survey.tiein import listed_positions

POSITION_CHECK_KEY = b"gyropipe.position_check"


class PositionCheck(BaseModel):
    """The file's own positions against the recomputed ones (lengths m)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    tolerance: float = Field(description="allowed 3-D difference at a survey's first station, m")
    relative: float = Field(description="allowance added per m of MD from the first station")
    compared: int = Field(description="stations whose file lists TVD, north and east")
    beyond_md: list[float] = Field(description="MD of each station beyond its tolerance, m")
    first_difference: float | None = Field(
        description="3-D difference at the first station beyond tolerance, m"
    )
    first_allowed: float | None = Field(description="its tolerance, m")
    worst_md: float | None = Field(description="MD of the largest difference, m")
    worst_difference: float | None = Field(description="the largest difference, m")

    def allowance(self) -> str:
        """The tolerance in words: "0.1 m + 0.1 m per km of MD"."""
        return f"{self.tolerance:g} m + {self.relative * 1000:g} m per km of MD"

    def summary(self) -> str:
        """One sentence: what was compared, and the first and worst disagreement."""
        if not self.beyond_md:
            return (
                f"the file's own TVD/north/east at {self.compared} stations agree with the "
                f"recomputed positions within {self.allowance()} (largest difference "
                f"{self.worst_difference or 0.0:.3f} m)"
            )
        return (
            f"the file's own TVD/north/east disagree with the recomputed positions at "
            f"{len(self.beyond_md)} of {self.compared} stations, first at MD "
            f"{self.beyond_md[0]:.2f} m by {self.first_difference:.3f} m (tolerance "
            f"{self.first_allowed:.3f} m: {self.allowance()}); largest {self.worst_difference:.3f}"
            f" m at MD {self.worst_md:.2f} m"
        )


def check_positions(
    stations: pa.Table,
    offsets: np.ndarray,
    computed: tuple[np.ndarray, np.ndarray, np.ndarray],
    tolerance: float,
    relative: float,
) -> PositionCheck | None:
    """The stations' own ``tvd``, ``north``, ``east`` (where all three are given and not
    null) against ``computed`` (TVD, north, east of each station, m); None when the file
    lists no position. ``offsets``: the CSR offsets of the table's surveys. Positions in
    another unit or north than the table's are refused
    (:func:`~pipeline.survey.tiein.listed_positions`)."""
    stated = listed_positions(stations)
    if stated is None:
        return None
    given = ~np.isnan(stated).any(axis=1)
    if not given.any():
        return None
    md = stations.column("md").to_numpy(zero_copy_only=False).astype(float)
    first = np.repeat(md[offsets[:-1]], np.diff(offsets))
    allowed = tolerance + relative * (md - first)
    difference = np.linalg.norm(stated - np.column_stack(computed), axis=1)
    beyond = given & (difference > allowed)
    worst = int(np.flatnonzero(given)[np.argmax(difference[given])])
    hit = np.flatnonzero(beyond)
    return PositionCheck(
        tolerance=tolerance,
        relative=relative,
        compared=int(given.sum()),
        beyond_md=[float(v) for v in md[hit]],
        first_difference=float(difference[hit[0]]) if hit.size else None,
        first_allowed=float(allowed[hit[0]]) if hit.size else None,
        worst_md=float(md[worst]),
        worst_difference=float(difference[worst]),
    )


def with_position_check(table: pa.Table, check: PositionCheck) -> pa.Table:
    """``table`` with ``check`` recorded in its schema metadata."""
    return with_record(table, POSITION_CHECK_KEY, check)


def position_check_of(table: pa.Table) -> PositionCheck | None:
    """The position check recorded in a table's schema metadata, if any."""
    return record_of(table, POSITION_CHECK_KEY, PositionCheck)
