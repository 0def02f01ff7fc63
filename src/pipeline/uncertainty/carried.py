"""The position uncertainty a stations file states, carried onto the trajectory integrated
from its stations: the one rule of what is carried and what is refused.

A stations file may list each station's uncertainty (a trajectory gyropipe wrote: Parquet,
CSV, LAS, WITSML ``matrixCov``). Those columns belong to their rows, so a trajectory
computed from the same stations keeps them row by row, each with its field metadata (error
model, confidence, description, :mod:`pipeline.uncertainty.stated`) and the file's tie-on
record (:mod:`pipeline.uncertainty.tieon`), and records that they came with the file
(:data:`~pipeline.uncertainty.stated.CARRIED_KEY`). A family of columns
(:data:`~pipeline.uncertainty.stated.FAMILIES`) is carried whole or not at all: one with
columns missing, in another unit, at a confidence level it does not state, holding a value
no such column can hold (a negative variance, an infinite size), a station's values partly
null, covariances of no covariance matrix, or in a north other than the azimuths' is
refused; so are 1σ ellipses that are not those of the covariances beside them (sizes, or the
azimuth of an ellipse with an axis; or whose semi-minor axis is the longer) and sizes at the
stated confidence that are not the 1σ ones scaled to it, and the refusal said — a file's
uncertainty is never dropped quietly. Lengths m, covariances m².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.uncertainty.ellipse import ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.stated import (
    CARRIED_KEY,
    CONFIDENCE_KEY,
    FAMILIES,
    INTERPOLATED_COLUMN,
    WORDS,
    Family,
    file_statements,
    unit_of,
)
from pipeline.uncertainty.tieon import TIE_ON_KEY, TieOnRecord, tie_on_of, with_tie_on

__all__ = [
    "FLAG_COLUMN",
    "Carried",
    "carried_uncertainty",
    "without_uncertainty",
]

FLAG_COLUMN = "outside_validity"
"""The per-station flag of no σ (outside the error model's range), carried with the σ."""
TIE_MD_M = 1e-3
"""A tie-on record's first MD agrees with its survey's first station within this (m): a
text file rounds MDs to 0.1 mm."""

PSD_M2 = 2e-8
"""How far below 0 (m²) a covariance's smallest eigenvalue may lie from its file's rounding:
8 decimals of m², the writers' (an error of at most 5e-9 an entry, 1.5e-8 on an eigenvalue)."""
PSD_REL = 1e-6
"""And in proportion to its largest variance (a file written to 6 or 7 significant digits)."""
ELLIPSE_M = 1e-3
"""How far (m) a 1σ size may lie from the one its covariances give, or a semi-minor axis
above its semi-major: 0.1 mm rounding of each, and of the covariances, 8 decimals of m²
(√5e-9 ≈ 0.07 mm at a size near 0), well within."""
ELLIPSE_REL = 1e-3
"""And in proportion to the size (a file written to fewer significant digits)."""
ELLIPSE_AZIMUTH_DEG = 0.1
"""deg: how far a stated ellipse azimuth may be from its covariances' (a file writing the
azimuth to 0.1° rounds by 0.05°; a covariance in another north is off by its convergence or
declination), where the ellipse has an axis: its semi-axes differ by more than
:data:`ELLIPSE_M` and :data:`ELLIPSE_REL` of the semi-major."""


@dataclass(frozen=True)
class Carried:
    """The uncertainty columns carried (fields with their metadata, and values), the file's
    tie-on record where it matches its stations, and each refusal in words."""

    fields: tuple[pa.Field, ...]
    columns: tuple[pa.ChunkedArray, ...]
    tie_on: TieOnRecord | None
    refused: tuple[str, ...]

    def onto(self, trajectory: pa.Table) -> pa.Table:
        """``trajectory`` (the stations' rows, in their order) with the carried columns,
        each recording that it came with the stations file, and the tie-on record."""
        for field, values in zip(self.fields, self.columns, strict=True):
            meta = {**(field.metadata or {}), CARRIED_KEY: b"stations file"}
            trajectory = trajectory.append_column(field.with_metadata(meta), values)
        return trajectory if self.tie_on is None else with_tie_on(trajectory, self.tie_on)


def carried_uncertainty(stations: pa.Table) -> Carried:
    """What of ``stations``' uncertainty columns a trajectory of its rows carries
    (module docstring); nothing, refusing nothing, for a table without them."""
    refused: list[str] = []
    kept: list[str] = []
    for family in FAMILIES:
        present = [c for c in family.columns if c in stations.column_names]
        if present:
            problem = _family_problem(stations, family, present)
            if problem is None:
                kept.extend(present)
            else:
                refused.append(f"columns {_listed(present)}: {problem}")
    disagree = _disagreement(stations, kept)
    if disagree is not None:
        refused.append(f"columns {_listed(kept)}: {disagree}")
        kept = []
    if kept:
        try:
            stated = file_statements(pa.schema([stations.schema.field(c) for c in kept]))
        except ValueError as exc:
            refused.append(f"columns {_listed(kept)}: {exc}")
            kept = []
        else:
            if "confidence" in stated and (off := _off_confidence(stations, kept, stated)):
                refused.append(f"columns {_listed(kept)}: {off}")
                kept = []
    if kept:  # the flags of the σ go with it: no σ outside the model, or between stations
        kept.extend(c for c in (FLAG_COLUMN, INTERPOLATED_COLUMN) if c in stations.column_names)
    tie_on = _tie_on(stations, refused) if kept else None
    return Carried(
        fields=tuple(stations.schema.field(c) for c in kept),
        columns=tuple(stations.column(c) for c in kept),
        tie_on=tie_on,
        refused=tuple(refused),
    )


def _family_problem(stations: pa.Table, family: Family, present: list[str]) -> str | None:
    """Why ``family``'s columns ``present`` cannot be carried, or None."""
    missing = [c for c in family.columns if c not in present]
    if missing:
        return f"without {_listed(missing)} (the {family.name} columns go all or none)"
    for name in present:
        field = stations.schema.field(name)
        meta = field.metadata or {}
        unit = meta.get(UNIT_KEY, b"").decode()
        wanted = unit_of(name)
        if unit != wanted:
            return f"{name} in {unit or 'no unit'!r}, expected {wanted!r}"
        if family.dimensions is not None and CONFIDENCE_KEY not in meta:
            return f"{name} states no confidence level (a size at an unknown level is no 1σ)"
        if not pa.types.is_floating(field.type):
            return f"{name} holds {field.type}, expected numbers"
        bad = _bad_row(name, stations.column(name).to_numpy(zero_copy_only=False))
        if bad is not None:
            md = float(stations.column("md")[bad].as_py())
            return f"{name} at MD {md:.2f} m holds {stations.column(name)[bad].as_py()!r}"
    problem = _row_problem(stations, family)
    if problem is not None:
        return problem
    if "ellipse_azimuth" in present:
        own = (stations.schema.field("ellipse_azimuth").metadata or {}).get(NORTH_KEY)
        azi = (stations.schema.field("azi").metadata or {}).get(NORTH_KEY)
        if own != azi:
            said = own.decode() if own else "none"
            return f"ellipse_azimuth in north reference {said!r}, not the azimuths'"
    return None


def _bad_row(name: str, values: np.ndarray) -> int | None:
    """The first row holding a value no such column holds (NaN, no σ, is one it does)."""
    values = np.asarray(values, dtype=np.float64)
    defined = ~np.isnan(values)
    ok = ~defined | np.isfinite(values)
    if name in ("cov_nn", "cov_ee", "cov_vv") or not name.startswith("cov_"):
        ok &= ~defined | (values >= 0)
    if name == "ellipse_azimuth":
        ok &= ~defined | (values < 180)
    bad = np.flatnonzero(~ok)
    return int(bad[0]) if bad.size else None


def _row_problem(stations: pa.Table, family: Family) -> str | None:
    """Why a station's values of ``family`` (all present, each a value such a column holds)
    are not one statement: some null where others are not (a hand edit's emptied cell:
    the rest then belongs to no σ), or covariances of no covariance matrix (an eigenvalue
    below 0 by more than the file's rounding, :data:`PSD_M2`: ``cov_ne² > cov_nn·cov_ee``)."""
    values = np.column_stack(
        [stations.column(c).to_numpy(zero_copy_only=False) for c in family.columns]
    ).astype(np.float64)
    null = np.isnan(values)
    md = stations.column("md").to_numpy(zero_copy_only=False)
    for row in np.flatnonzero(null.any(axis=1) & ~null.all(axis=1)).tolist():
        empty = [c for c, n in zip(family.columns, null[row], strict=True) if n]
        return (
            f"at MD {md[row]:.2f} m {_listed(empty)} null where the other {family.name} "
            "columns are not (a station's are all stated or all null)"
        )
    if family.name != "covariance":
        return None
    whole = ~null.any(axis=1)
    nn, ne, nv, ee, ev, vv = values[whole].T
    matrices = np.stack(
        [np.stack(r, axis=-1) for r in ((nn, ne, nv), (ne, ee, ev), (nv, ev, vv))], axis=-2
    )
    least = np.linalg.eigvalsh(matrices)[:, 0] if len(nn) else np.zeros(0)
    allowed = PSD_M2 + PSD_REL * np.max(np.stack((nn, ee, vv)), axis=0, initial=0.0)
    bad = np.flatnonzero(least < -allowed)
    if not bad.size:
        return None
    row = int(np.flatnonzero(whole)[bad[0]])
    return (
        f"at MD {md[row]:.2f} m the covariances are no covariance matrix: its smallest "
        f"eigenvalue is {least[bad[0]]:.3g} m² (a covariance has none below 0; check "
        "cov_ne² ≤ cov_nn·cov_ee and the other off-diagonal entries)"
    )


def _disagreement(stations: pa.Table, kept: list[str]) -> str | None:
    """Why the 1σ ellipses (``ellipse_major``, ``ellipse_minor``, ``sigma_v``) of ``kept``
    are not those of its covariances, kept with them (two uncertainties, a hand edit's), to
    :data:`ELLIPSE_M` and :data:`ELLIPSE_REL` of a size and :data:`ELLIPSE_AZIMUTH_DEG` of
    the azimuth of an ellipse with an axis; or a semi-minor axis longer than
    its semi-major (no such ellipse) beyond :data:`ELLIPSE_M`; None where they agree."""
    if "ellipse_major" not in kept:
        return None

    md = _floats(stations, "md")
    major, minor, sigma_v = (
        _floats(stations, c) for c in ("ellipse_major", "ellipse_minor", "sigma_v")
    )
    longer = np.flatnonzero(minor > major + ELLIPSE_M)
    if longer.size:
        row = int(longer[0])
        return (
            f"at MD {md[row]:.2f} m ellipse_minor {minor[row]:g} m exceeds ellipse_major "
            f"{major[row]:g} m (no ellipse's semi-minor axis is its longer)"
        )
    if "cov_nn" not in kept:
        return None
    of = ellipses(*(_floats(stations, c) for c in ("cov_nn", "cov_ne", "cov_ee", "cov_vv")))
    for name, stated, computed in (
        ("ellipse_major", major, of.semi_major),
        ("ellipse_minor", minor, of.semi_minor),
        ("sigma_v", sigma_v, of.sigma_v),
    ):
        off = np.abs(stated - computed) > ELLIPSE_M + ELLIPSE_REL * np.abs(computed)
        if (bad := np.flatnonzero(off)).size:  # (NaN compares false: no σ, nothing to agree)
            row = int(bad[0])
            return (
                f"at MD {md[row]:.2f} m {name} is {stated[row]:.4f} m, the covariances' "
                f"{computed[row]:.4f} m (the file states two uncertainties that disagree)"
            )
    if "ellipse_azimuth" in kept:
        stated_deg = _floats(stations, "ellipse_azimuth")
        computed_deg = np.degrees(of.azimuth)
        off = np.abs(np.mod(stated_deg - computed_deg + 90.0, 180.0) - 90.0)
        axis = of.semi_major - of.semi_minor > ELLIPSE_M + ELLIPSE_REL * of.semi_major
        if (bad := np.flatnonzero(axis & (off > ELLIPSE_AZIMUTH_DEG))).size:
            row = int(bad[0])
            return (
                f"at MD {md[row]:.2f} m ellipse_azimuth is {stated_deg[row]:.2f}°, the "
                f"covariances' {computed_deg[row]:.2f}° (the ellipse and the covariances are "
                "turned apart: one of them in another north, or edited)"
            )
    return None


def _off_confidence(stations: pa.Table, kept: list[str], stated: dict[str, str]) -> str | None:
    """Why the sizes at the stated confidence of ``kept`` are not the 1σ ones (the
    covariances', else the 1σ ellipse columns') scaled to it — k of χ²₂ for the ellipse's
    axes, the two-sided normal quantile for the vertical — to :data:`ELLIPSE_M` and
    :data:`ELLIPSE_REL`; None where they agree or there is nothing to compare."""

    confidence = float(stated["confidence"])
    if "cov_nn" in kept:
        of = ellipses(*(_floats(stations, c) for c in ("cov_nn", "cov_ne", "cov_ee", "cov_vv")))
        one = {"major": of.semi_major, "minor": of.semi_minor, "vertical": of.sigma_v}
    elif "ellipse_major" in kept:
        one = {k: _floats(stations, c) for k, c in _ONE_SIGMA.items()}
    else:
        return None
    md = _floats(stations, "md")
    k2, k1 = horizontal_scale(confidence), vertical_scale(confidence)
    for name, axis, k in (
        ("ellipse_major_conf", "major", k2),
        ("ellipse_minor_conf", "minor", k2),
        ("vertical_conf", "vertical", k1),
    ):
        if name not in kept:
            continue
        expected = k * one[axis]
        stated_m = _floats(stations, name)
        off = np.abs(stated_m - expected) > ELLIPSE_M + ELLIPSE_REL * np.abs(expected)
        if (bad := np.flatnonzero(off)).size:
            row = int(bad[0])
            return (
                f"at MD {md[row]:.2f} m {name} is {stated_m[row]:.4f} m, not the 1σ "
                f"{one[axis][row]:.4f} m at the {confidence * 100:g} % confidence the file "
                f"states ({k:.4f} × 1σ = {expected[row]:.4f} m)"
            )
    return None


_ONE_SIGMA = {"major": "ellipse_major", "minor": "ellipse_minor", "vertical": "sigma_v"}
"""The 1σ column of each axis."""


def _floats(stations: pa.Table, name: str) -> np.ndarray:
    """Column ``name`` of ``stations`` as float64 (nulls NaN)."""
    return np.asarray(stations.column(name).to_numpy(zero_copy_only=False), np.float64)


def _tie_on(stations: pa.Table, refused: list[str]) -> TieOnRecord | None:
    """The file's tie-on record where each survey's first station is its (a refusal in
    ``refused`` where it is not: it states another table's)."""
    if TIE_ON_KEY not in (stations.schema.metadata or {}) or stations.num_rows == 0:
        return None  # (no stations: no survey starts, and no uncertainty to state)
    record = tie_on_of(stations)
    assert record is not None
    md = stations.column("md").to_numpy(zero_copy_only=False)
    names = stations.column("survey").to_pylist() if "survey" in stations.column_names else None
    firsts = [0] + [i for i in range(1, len(md)) if names is not None and names[i] != names[i - 1]]
    found = [(None if names is None else names[i], float(md[i])) for i in firsts]
    stated = [(t.survey, t.md) for t in record.surveys]
    if len(found) == len(stated) and all(
        s == f and abs(m - n) <= TIE_MD_M for (s, m), (f, n) in zip(stated, found, strict=True)
    ):
        return record
    refused.append(
        "the tie-on statement (where each survey's uncertainty starts): it names surveys "
        f"starting at {_starts(stated)}, the stations start at {_starts(found)}"
    )
    return None


def _starts(firsts: list[tuple[str | None, float]]) -> str:
    return ", ".join(f"MD {md:.2f} m" + (f" ({s})" if s is not None else "") for s, md in firsts)


def _listed(names: list[str]) -> str:
    return ", ".join(names)


def without_uncertainty(table: pa.Table) -> pa.Table:
    """``table`` less its uncertainty columns and tie-on record (a stage computing its own)."""
    drop = [c for c in (*WORDS, FLAG_COLUMN) if c in table.column_names]
    meta = {k: v for k, v in (table.schema.metadata or {}).items() if k != TIE_ON_KEY}
    return table.drop_columns(drop).replace_schema_metadata(meta)
