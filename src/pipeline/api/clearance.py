"""``gp.clearance``: anti-collision scan of a reference well against offset wells."""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.anticollision.offset_north import listed_tie, taken_words, true_azimuths
from pipeline.anticollision.tables import OffsetWells
from pipeline.api import stages
from pipeline.api.frames import (
    TableLike,
    WellLike,
    like,
    to_frame,
    to_table,
    well_metadata,
    well_of_data,
)
from pipeline.errors import ParameterError
from pipeline.stages import toolmodels
from pipeline.stages.clearance import offset_tables
from pipeline.tables import Stations
from pipeline.well import WellMetadata

OffsetsLike = str | Path | Mapping[str, "TableLike | str | Path"] | Sequence[TableLike]
"""Offset wells: a manifest file, a mapping of well id → stations (table or file), or a
sequence of stations tables named by their well metadata."""


def clearance(
    reference: TableLike | str | Path,
    offsets: OffsetsLike,
    *,
    offset_model: str | Mapping[str, str] = "ISCWSA-MWD-REV5.11",
    offset_hole_diameter: float | Mapping[str, float] | None = None,
    offset_position: Mapping[str, Sequence[float]] | None = None,
    offset_kickoff: Mapping[str, float] | None = None,
    well: WellLike = None,
    **params: Any,
) -> TableLike:
    """ISCWSA separation factor of every reference station against each offset well: per
    offset well and reference MD, the closest point's ``offset_md``, ``distance``
    (centre-to-centre, m), ``sigma_s`` (m), ``sf`` and its ``level`` (pass/warn/fail), and
    the travelling-cylinder ``toolface`` (deg from the reference's high side).

    ``reference``: its stations (table or file). ``offsets``: a manifest CSV (well id, file,
    tool model, hole diameter, first-station position; see docs/clearance.md), or stations
    by well id, or stations tables named by their well metadata; then ``offset_model``,
    ``offset_hole_diameter`` (m) and ``offset_position`` ((north, east[, tvd]) m from the
    reference wellhead, default (0, 0): its slot, its first station there plus the tie-on
    its stations list there, if they do; TVD default the listed one, else the first MD)
    give each well's, as one value or
    by well id; ``offset_kickoff`` names sidetracks of the reference, well id → kick-off MD
    on the reference (m) (a well whose first station lies on the reference path is found
    without it; the manifest's ``parent`` and ``kickoff_md`` columns). Each offset's
    azimuths are referred to true north by its own declination or grid convergence (its
    file's or well metadata's, not ``well``'s; a grid one stating none takes the
    reference's, with a warning). ``params``: the
    stage's (``reference_model``, ``reference_hole_diameter`` m, ``k``, ``sigma_pa`` m,
    ``surface_margin`` m, ``stop``, ``caution``, ``level_on``, ``first_station_exact``,
    ``vertical_azimuth``, ``common_tolerance`` m, ``latitude``, ``magnetic``,
    ``outside_validity``: refuse or flag a station outside its model's range). Returns the
    kind of table ``reference`` is (a DataFrame for a file).
    """
    reg = stages.registry()
    given = well_metadata(well)
    ref: TableLike
    if isinstance(reference, str | Path):
        ref, header = reg.read(Path(reference), "stations", well=given)
        ref_well = header.merged(given)
        template: TableLike = to_frame(ref)
    else:
        ref, ref_well, template = reference, well_of_data(reference).merged(given), reference
    if isinstance(offsets, str | Path):
        wells, stations = offset_tables(
            Path(offsets),
            lambda p: reg.read(p, "stations", well=given),  # the caller's, not the reference's
            ref_well,
            toolmodels.of_registry(reg),
        )
    else:
        wells, stations = _offsets(
            offsets,
            offset_model,
            offset_hole_diameter,
            offset_position,
            offset_kickoff,
            given,
            ref_well,
        )
    inputs = {"reference": ref, "offsets": stations, "wells": wells}
    outs, _, _ = stages.call("clearance", inputs, params, well=ref_well)
    return like(template, outs["clearance"])


def _each(value: Any, name: str, what: str) -> Any:
    """``value`` for well ``name``: the value itself, or its entry in a mapping."""
    if isinstance(value, Mapping):
        if name not in value:
            raise ParameterError(f"clearance: no {what} for offset well {name!r}")
        return value[name]
    return value


def _offsets(
    offsets: Mapping[str, TableLike | str | Path] | Sequence[TableLike],
    model: str | Mapping[str, str],
    diameter: float | Mapping[str, float] | None,
    position: Mapping[str, Sequence[float]] | None,
    kickoff: Mapping[str, float] | None,
    given: WellMetadata,
    well: WellMetadata,
) -> tuple[pa.Table, pa.Table]:
    """The wells and stations tables of offsets given one by one: each read (or a table
    taken) with the caller's ``given`` well metadata as its defaults — never the reference
    file's header (its north) — and referred to true north by its own corrections, else the
    reference ``well``'s grid convergence (:func:`true_azimuths`)."""
    if diameter is None:
        raise ParameterError("clearance: give offset_hole_diameter (m) or a manifest")
    named = offsets if isinstance(offsets, Mapping) else _named(offsets)
    if not named:
        raise ParameterError("clearance: no offset wells given")
    unknown = sorted(set(kickoff or {}) - set(named))
    if unknown:
        raise ParameterError(f"clearance: offset_kickoff names no offset well: {unknown}")
    reg = stages.registry()
    tables: dict[str, pa.Table] = {}
    true: dict[str, np.ndarray] = {}
    taken: dict[str, float | None] = {}
    ties: dict[str, dict[str, float | None]] = {}
    for name, data in named.items():
        if isinstance(data, str | Path):
            tables[name], header = reg.read(Path(data), "stations", well=given)
        else:
            header = well_of_data(data)
            own = given.merged(header)
            tables[name] = to_table(data, Stations, what=f"offset well {name!r}", well=own)
        try:
            true[name], shift, convergence = true_azimuths(tables[name], header, well)
            ties[name] = listed_tie(tables[name], shift)
        except ValueError as exc:
            raise ParameterError(
                f"clearance: offset well {name!r}: {exc}: state it in its well metadata"
            ) from None
        if convergence is not None:
            warnings.warn(
                f"clearance: offset well {name!r}: {taken_words(convergence)}", stacklevel=3
            )
        taken[name] = convergence
    stations = Stations.compiled().make_table(
        {
            "survey": [name for name, t in tables.items() for _ in range(t.num_rows)],
            "md": np.concatenate([t.column("md").to_numpy() for t in tables.values()]),
            "inc": np.concatenate([t.column("inc").to_numpy() for t in tables.values()]),
            "azi": np.concatenate(list(true.values())),
        },
        north_reference="true",
    )
    rows = []
    for name in tables:
        at = list(_each(position, name, "offset_position") if position is not None else (0, 0))
        if len(at) not in (2, 3):
            raise ParameterError(f"clearance: offset_position of {name!r}: (north, east[, tvd])")
        rows.append(
            {
                "offset": name,
                "model": _each(model, name, "offset_model"),
                "hole_diameter": float(_each(diameter, name, "offset_hole_diameter")),
                "north": float(at[0]),
                "east": float(at[1]),
                "tvd": float(at[2]) if len(at) == 3 else None,
                "parent": "reference" if kickoff and name in kickoff else None,
                "kickoff_md": float(kickoff[name]) if kickoff and name in kickoff else None,
                "reference_convergence": taken[name],
                **ties[name],
            }
        )
    wells = OffsetWells.compiled().make_table({k: [r[k] for r in rows] for k in rows[0]})
    return wells, stations


def _named(offsets: Sequence[TableLike]) -> dict[str, TableLike]:
    """Stations tables by their well metadata's name (``offset-<k>`` without one)."""
    out: dict[str, TableLike] = {}
    for k, data in enumerate(offsets, 1):
        name = well_of_data(data).well or f"offset-{k}"
        if name in out:
            raise ParameterError(f"clearance: two offset wells are named {name!r}")
        out[name] = data
    return out
