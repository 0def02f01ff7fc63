"""An offset well's azimuths referred to true north by its own corrections, never another
well's: a declination is of a site and a date (secular change is tenths of a degree a year),
a grid convergence of a grid and a place; the tie-on its stations file lists turned with
them, and where its first station lies. Angles in degrees, east of true north positive;
lengths in m."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.survey.north import convert_azimuth, turned_positions
from pipeline.survey.stations import north_reference_of, survey_offsets
from pipeline.survey.tiein import listed_ties
from pipeline.well import WellMetadata

__all__ = ["first_station", "listed_tie", "on_the_reference_grid", "taken_words", "true_azimuths"]

TIE_COLUMNS = ("tie_tvd", "tie_north", "tie_east")
"""The offset-wells columns of the tie-on an offset's stations file lists (m)."""


def true_azimuths(
    table: pa.Table, own: WellMetadata, reference: WellMetadata
) -> tuple[np.ndarray, float, float | None]:
    """A stations table's azimuths (deg, NaN kept) referred to true north by ``own`` (its
    well's metadata: its declination; of grid azimuths the convergence applied to them,
    else its grid convergence), the change δ that made (deg, A_true = A + δ mod 360: what
    turns the positions it lists, :func:`~pipeline.survey.north.turned_positions`), and
    the ``reference`` well's grid convergence where grid
    azimuths took it, stating none of their own (else None; the scan refuses it unless the
    reference is on grid north by it: :func:`on_the_reference_grid`).

    Raises ``ValueError``: magnetic azimuths without a declination, grid ones without a
    convergence where the reference states none."""
    north = north_reference_of(table, "azi")
    declination = own.declination if north == "magnetic" else None
    convergence = own.convergence_for("grid") if north == "grid" else None
    taken = None
    if north == "magnetic" and declination is None:
        raise ValueError(
            "magnetic-north azimuths and no declination of its own (another well's, of "
            "another site or date, is not its)"
        )
    if north == "grid" and convergence is None:
        taken = convergence = reference.convergence_for("grid")
        if convergence is None:
            raise ValueError(
                "grid-north azimuths and no grid convergence of its own, nor the reference well's"
            )
    azi = table.column("azi").to_numpy(zero_copy_only=False)
    true, _ = convert_azimuth(
        azi, north, "true", convergence_deg=convergence, declination_deg=declination
    )
    shift, _ = convert_azimuth(
        0.0, north, "true", convergence_deg=convergence, declination_deg=declination
    )
    return np.where(np.isnan(azi), np.nan, true), float(shift), taken


def listed_tie(table: pa.Table, shift: float) -> dict[str, float | None]:
    """The TVD, north and east (m, from its own wellhead) an offset's stations file lists at
    its first station, horizontal ones turned by ``shift`` (deg, :func:`true_azimuths`' δ)
    to true north as its azimuths are, by the names of :data:`TIE_COLUMNS` (all None: it
    lists not all three there)."""
    listed = listed_ties(table, survey_offsets(table)[:2])[0]
    if listed is None:
        return dict.fromkeys(TIE_COLUMNS)
    north, east = turned_positions(listed[1], listed[2], shift)
    return dict(zip(TIE_COLUMNS, (float(listed[0]), float(north), float(east)), strict=True))


def first_station(
    well: Mapping[str, Any], md0: float, tie: Mapping[str, float] | None
) -> tuple[float, float, float]:
    """Where an offset well's first station is (north, east, TVD, m, the scan's north): its
    slot (the wells table's ``north``, ``east``) plus the north and east of the ``tie`` its
    stations file lists there (TVD, north, east from its own wellhead, in the scan's north;
    None: none listed); TVD the wells table's, else the file's, else its first MD ``md0``."""
    tvd = well["tvd"] if well["tvd"] is not None else (md0 if tie is None else tie["tvd"])
    if tie is None:
        return well["north"], well["east"], tvd
    return well["north"] + tie["north"], well["east"] + tie["east"], tvd


def taken_words(convergence: float) -> str:
    """What a warning says of grid azimuths that took the reference's ``convergence``."""
    return (
        "grid-north azimuths and no grid convergence of its own: the reference well's grid "
        f"convergence ({convergence}°) taken: the same grid assumed"
    )


def on_the_reference_grid(
    name: str, taken: float | None, north: str, convergence: float | None
) -> None:
    """Refuse offset well ``name`` whose grid azimuths took the reference's convergence
    ``taken`` (:func:`true_azimuths`) unless the reference's azimuths are on ``north`` =
    grid by that ``convergence``."""
    if taken is not None and (north != "grid" or convergence != taken):
        raise ValueError(
            f"offset well {name!r}: its grid-north azimuths took the reference well's grid "
            f"convergence ({taken}°), but the reference's azimuths are {north} north"
            + (f" by {convergence}°" if north == "grid" else "")
            + ": give its own grid convergence"
        )
