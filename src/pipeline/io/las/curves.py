"""Curves of a LAS file as the columns of a table kind (stations, samples): the curve read
for each column, its unit, the azimuths' north reference, and the kind's table of their
values in canonical units.

* **Curves** — a mnemonic names a canonical column through
  :func:`pipeline.io.mnemonics.canonical_name` (``DEPT``→md, ``AZIM``→azi, ``GX``→acc_x,
  ``WX``→gyro_x, ``BZ``→mag_z…) or the option ``columns``; an azimuth mnemonic may end in
  its north reference (``AZTN``, ``AZGN``, ``AZI_MN``). Other curves are left out. Units
  come from the curve line (the option ``units`` wins) and are converted to canonical units
  with :func:`pipeline.units.conversion_factor`; a needed curve without a known unit is an
  error saying how to declare it.
* **North reference** (stations) — named by the azimuth mnemonic, a word of its description
  (``Azimuth (true north)``, ``Grid azimuth``, ``MN``; not one before a correction,
  ``mag dec applied``, nor any in a description with a negation, ``not grid corrected``),
  an ``NREF`` item (or ``NORTHREF``, ``AZIREF``, ``AZREF``) in ``~W``/``~P``, or the option
  ``north_reference``: all must agree; ``default_north_reference`` applies when none names
  one. ``mag corrected`` names none and is ambiguous (true north, declination applied, or
  magnetic, interference corrected): refused at its line unless an NREF item or the option
  names the north.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

import numpy as np
import pyarrow as pa

from pipeline.contracts import SOURCE_LINE, UNIT_KEY, TableContract
from pipeline.errors import InputFileError, UnitError, WrongKindError
from pipeline.io.las.header import Header, Item, mnemonics
from pipeline.io.las.log import describe
from pipeline.io.las.options import LasOptions
from pipeline.io.las.rows import Data, Floats, Lines, Mask
from pipeline.io.mnemonics import CURVES, canonical_name, normalise
from pipeline.io.numbers import scaled
from pipeline.io.uncertainty_columns import UNCERTAINTY_COLUMNS
from pipeline.tables import RawSamples, Stations
from pipeline.units import canonical_unit, conversion_factor, is_unit_of
from pipeline.well import NORTH_WORDS, NorthReference

NORTH_SUFFIXES: dict[str, NorthReference] = {"TN": "true", "GN": "grid", "MN": "magnetic"}
"""Endings of an azimuth mnemonic naming its north reference."""
NORTH_ITEMS = ("NREF", "NORTHREF", "AZIREF", "AZREF")
NEGATIONS = frozenset({"not", "no", "non", "without"})
"""Words making a description's north words no reference (``Azimuth, not grid corrected``)."""
CORRECTIONS = frozenset({"dec", "decl", "declination", "conv", "convergence", "corr", "correction"})
"""Words after which a north word names a correction, not the reference (``mag dec applied``:
true north)."""
AMBIGUOUS = "corrected"
"""The word after which magnetic north names no reference (``mag corrected``): vendors write
it of azimuths turned to true north (declination applied) and of magnetic ones corrected
for drillstring interference."""


@dataclass(frozen=True)
class Kind:
    """A table kind the reader makes: its contract, its columns in order, the required ones
    and the one that may not be null (the survey's own index)."""

    contract: type[TableContract]
    columns: tuple[str, ...]
    required: tuple[str, ...]
    key: str


KINDS = {
    "stations": Kind(
        Stations,
        ("survey", "md", "inc", "azi", "tvd", "north", "east", "dls", *UNCERTAINTY_COLUMNS),
        ("md", "inc", "azi"),
        "md",
    ),
    "samples": Kind(
        RawSamples,
        tuple(RawSamples.model_fields),
        ("time", "gyro_x", "acc_x", "acc_y", "acc_z"),
        "time",
    ),
}
INTEGER_COLUMNS = frozenset({"station", "position"})
TEXT_COLUMNS = frozenset({"survey"})


# ---------------------------------------------------------------------------- curves


def _recognise(item: Item) -> str | None:
    """The canonical column a curve's mnemonic names, if any."""
    return "azi" if _suffix_north(item.mnemonic) else canonical_name(item.mnemonic)


def _suffix_north(mnemonic: str) -> NorthReference | None:
    """The north reference an azimuth mnemonic ends with (``AZTN``, ``AZI_GN``), if any."""
    key = normalise(mnemonic)
    for suffix, ref in NORTH_SUFFIXES.items():
        stem = key.removesuffix(suffix)
        if stem != key and (stem == "AZ" or canonical_name(stem) == "azi"):
            return ref
    return None


def choose(
    path: Path,
    header: Header,
    spec: Kind,
    opts: LasOptions,
    declared: list[tuple[str, NorthReference]],
) -> dict[str, int]:
    """The ~Curve position of each column of the kind the file has."""
    curves = header.curves
    chosen: dict[str, int] = {}
    for name, mnemonic in opts.columns.items():
        if name not in spec.columns:
            raise InputFileError(
                path, f"option columns: {name} is not read here (read: {', '.join(spec.columns)})"
            )
        matches = [i for i, c in enumerate(curves) if normalise(c.mnemonic) == normalise(mnemonic)]
        if len(matches) != 1:
            raise InputFileError(
                path,
                f"option columns: {name}: {mnemonic!r} names "
                + (f"{len(matches)} curves" if matches else "no curve")
                + f"; curves: {mnemonics(curves)}",
                line=curves[matches[1]].line if matches else 0,
            )
        chosen[name] = matches[0]
    found: dict[str, list[int]] = {}
    for i, curve in enumerate(curves):
        guess = _recognise(curve)
        if guess in spec.columns and guess not in chosen and i not in chosen.values():
            found.setdefault(guess, []).append(i)
    refs = {ref for _, ref in declared} | {opts.north_reference}
    for name, indices in found.items():
        if len(indices) > 1 and name == "azi":  # the one of the declared north reference
            indices = [i for i in indices if set(_curve_north(curves[i])) & refs] or indices
        quantity = CURVES[name].quantity
        if len(indices) > 1 and quantity is not None:  # the unit tells: DOGLEG.deg is no DLS
            indices = [i for i in indices if is_unit_of(curves[i].unit, quantity)] or indices
        if len(indices) > 1:
            raise InputFileError(
                path,
                f"several curves look like {name}: "
                f"{', '.join(curves[i].mnemonic for i in indices)}; choose one with the option "
                f"columns (e.g. columns: {{{name}: {curves[indices[0]].mnemonic}}})"
                + (" or north_reference" if name == "azi" else ""),
                line=curves[indices[1]].line,
            )
        chosen[name] = indices[0]
    _require(path, header, spec, chosen)
    return chosen


WHAT = {"stations": "survey stations", "samples": "raw sensor samples"}
NEEDS = {"stations": "MD, INC, AZI", "samples": "TIME, WX, GX, GY, GZ"}
"""Each kind in words, and the curves it needs (their usual mnemonics)."""


def _require(path: Path, header: Header, spec: Kind, chosen: dict[str, int]) -> None:
    """Every required column has a curve; else a :class:`WrongKindError`: short when the
    file has none of the kind's curves but its index (a log of other curves), else listing
    the mnemonics accepted for each missing one."""
    missing = [name for name in spec.required if name not in chosen]
    if not missing:
        return
    kind = next(k for k, v in KINDS.items() if v is spec)
    if not any(n in chosen for n in spec.required if n != spec.key):
        raise WrongKindError(path, f"{describe(header)}; not {WHAT[kind]} (needs {NEEDS[kind]})")
    accepted = "; ".join(f"{n}: {', '.join(CURVES[n].aliases)}" for n in missing)
    raise WrongKindError(
        path,
        f"no curve for {', '.join(missing)}; curves: {mnemonics(header.curves)}; "
        f"accepted mnemonics: {accepted}; or name the curve with the option columns "
        f"(e.g. columns: {{{missing[0]}: MNEMONIC}})",
        line=header.curves[0].line,
    )


def factor(path: Path, curve: Item, name: str, opts: LasOptions) -> float:
    """Factor from the curve's unit (the option ``units`` wins) to the canonical unit."""
    quantity = CURVES[name].quantity
    if quantity is None:
        return 1.0
    unit = opts.units.get(name) or curve.unit
    canonical = canonical_unit(quantity)
    how = (
        f"declare it in the ~Curve line (e.g. '{curve.mnemonic}.{canonical} : ...') or with "
        f"the option units (e.g. units: {{{name}: {canonical}}})"
    )
    if not unit:
        raise InputFileError(
            path, f"curve {curve.mnemonic} ({name}) has no unit: {how}", curve.line, curve.mnemonic
        )
    try:
        return conversion_factor(unit, quantity)
    except UnitError as exc:
        raise InputFileError(
            path, f"curve {curve.mnemonic} ({name}): {exc}; {how}", curve.line, curve.mnemonic
        ) from None


# ------------------------------------------------------------------- north reference


def _north_word(path: Path, item: Item) -> NorthReference:
    """The reference an NREF-like item's value names: one of the :data:`NORTH_WORDS`."""
    words = {w for w in re.split(r"[^0-9a-z]+", item.value.casefold()) if w} - {"north"}
    if len(words) == 1 and (word := words.pop()) in NORTH_WORDS:
        return NORTH_WORDS[word]
    raise InputFileError(
        path, f"{item.mnemonic} {item.value!r}: expected true, grid or magnetic", line=item.line
    )


def declared_north(path: Path, header: Header) -> list[tuple[str, NorthReference]]:
    """(where, reference) of each NREF-like item."""
    return [
        (f"{item.mnemonic} on line {item.line}", _north_word(path, item))
        for item in header.well + header.parameters
        if item.mnemonic in NORTH_ITEMS and item.value
    ]


def _curve_north(item: Item) -> set[NorthReference]:
    """North references an azimuth curve names by its mnemonic's ending or description
    (:data:`NEGATIONS`, :data:`CORRECTIONS` and :data:`AMBIGUOUS`: where the description
    names none)."""
    words = _words(item)
    refs = set()
    if not NEGATIONS & set(words):
        refs = {
            NORTH_WORDS[w]
            for w, after in pairwise([*words, ""])
            if w in NORTH_WORDS and after not in CORRECTIONS and not _ambiguous(w, after)
        }
    suffix = _suffix_north(item.mnemonic)
    return refs | {suffix} if suffix else refs


def _words(item: Item) -> list[str]:
    return [w for w in re.split(r"[^0-9a-z]+", item.descr.casefold()) if w]


def _ambiguous(word: str, after: str) -> bool:
    return after == AMBIGUOUS and NORTH_WORDS.get(word) == "magnetic"


def one_north(
    path: Path, sources: list[tuple[str, NorthReference]], curve: Item | None = None
) -> NorthReference | None:
    """The one north reference ``sources`` ((where, reference)) name, if any."""
    refs = sorted({ref for _, ref in sources})
    if len(refs) > 1:
        raise InputFileError(
            path,
            "conflicting north references: " + ", ".join(f"{r} ({s})" for s, r in sources),
            curve.line if curve else 0,
            curve.mnemonic if curve else "",
        )
    return refs[0] if refs else None


def azimuth_north(
    path: Path, azi: Item, declared: list[tuple[str, NorthReference]], opts: LasOptions
) -> tuple[NorthReference, NorthReference | None]:
    """The azimuths' north reference, and the one the file itself names."""
    in_file = [(f"curve {azi.mnemonic} on line {azi.line}", r) for r in _curve_north(azi)]
    in_file += declared
    option = [("option north_reference", opts.north_reference)] if opts.north_reference else []
    words = _words(azi)
    if not in_file + option and any(_ambiguous(*pair) for pair in pairwise(words)):
        raise InputFileError(
            path,
            f"curve {azi.mnemonic} {azi.descr!r}: ambiguous north reference (magnetic "
            "corrected: turned to true north, or magnetic with interference corrected?): "
            "add a ~Well line 'NREF.  true : north reference' or set the option "
            "north_reference",
            azi.line,
            azi.mnemonic,
        )
    north = one_north(path, in_file + option, azi) or opts.default_north_reference
    if north is None:
        raise InputFileError(
            path,
            f"no north reference for the azimuths: name it in the curve description "
            f"('{azi.mnemonic}.DEG : Azimuth (true north)'), add a ~Well line "
            "'NREF.  grid : north reference', or set the option north_reference "
            "(or the well's north_reference)",
            azi.line,
            azi.mnemonic,
        )
    return north, one_north(path, in_file, azi)


# ----------------------------------------------------------------------------- table


def columns(
    path: Path,
    spec: Kind,
    header: Header,
    chosen: dict[str, int],
    data: Data,
    masks: dict[int, Mask],
    factors: dict[str, float],
) -> dict[str, pa.Array]:
    """The table's columns in canonical units, in the kind's order, with nulls."""
    columns: dict[str, pa.Array] = {}
    for name in (n for n in spec.columns if n in chosen):
        i = chosen[name]
        values, mask = data.values[i], masks[i]
        if name in INTEGER_COLUMNS:
            columns[name] = _integers(path, values, mask, data.lines, header.curves[i])
        elif name in TEXT_COLUMNS:
            columns[name] = _labels(values, mask)
        else:
            factor = factors[name]
            columns[name] = _with_nulls(scaled(values, factor) if factor != 1.0 else values, mask)
    columns[SOURCE_LINE] = pa.array(data.lines)
    return columns


def _with_nulls(values: Floats, mask: Mask) -> pa.Array:
    """float64 ``values`` (no copy) with nulls where ``mask``; the validity bitmap packed by
    numpy (``pa.array(values, mask=mask)`` packs it ~15× slower: 0.15 ms a block)."""
    if not mask.any():
        return pa.array(values)
    valid = np.packbits(~mask, bitorder="little")
    data = np.ascontiguousarray(values, np.float64)
    return pa.Array.from_buffers(pa.float64(), data.size, [pa.py_buffer(valid), pa.py_buffer(data)])


def _integers(path: Path, values: Floats, mask: Mask, lines: Lines, curve: Item) -> pa.Array:
    bad = np.flatnonzero(~mask & ((values != np.round(values)) | (np.abs(values) > 2.0**53)))
    if bad.size:
        raise InputFileError(
            path,
            f"expected a whole number, got {values[bad[0]]!r}",
            line=int(lines[bad[0]]),
            column=curve.mnemonic,
        )
    return pa.array(np.where(mask, 0, values).astype(np.int64), mask=mask if mask.any() else None)


def _labels(values: Floats, mask: Mask) -> pa.Array:
    """Text labels (survey ids) of a numeric curve: ``3.0`` → ``'3'``."""
    return pa.array(
        [
            None if null else f"{v:.0f}" if v.is_integer() else repr(v)
            for v, null in zip(values.tolist(), mask.tolist(), strict=True)
        ],
        pa.string(),
    )


def make_table(spec: Kind, columns: dict[str, pa.Array], north: str | None) -> pa.Table:
    """The contract's table; columns outside the contract get their canonical unit."""
    table = spec.contract.compiled().make_table(columns, north_reference=north)
    known = {c.name for c in spec.contract.compiled().columns}
    fields = []
    for f in table.schema:
        quantity = CURVES[f.name].quantity if f.name in CURVES else None
        if f.name not in known and quantity is not None:
            f = f.with_metadata({UNIT_KEY: canonical_unit(quantity).encode()})
        fields.append(f)
    return pa.Table.from_arrays(table.columns, schema=pa.schema(fields))
