"""A LAS file's statement of where its uncertainty curves start: the tie-on record
(:mod:`pipeline.uncertainty.tieon`) as ~Parameter items, one set per survey ``k`` (1, 2, …
in the record's order), ``MNEM.UNIT  VALUE : DESCRIPTION`` as LAS 2.0 has them:

* ``TIEMDk .m`` — the survey's first station's MD (its tie-on), m;
* ``TIEBASISk`` — ``wellhead``, ``survey``, ``given`` or ``not included``;
* ``TIESURVEYk`` — its survey id, written where the file has the survey curve;
* ``TIEPARENTk`` — basis ``survey``: the survey it is tied on;
* ``TIESEMIk .m`` — basis ``given``: the given covariance's horizontal semi-major axis, 1σ.

No JSON: a LAS value ends at its first colon (lasio's grammar), and JSON holds colons.
The reader refuses, at its line, a set it cannot read back as the writer wrote it.
"""

from __future__ import annotations

import re
from pathlib import Path

from pydantic import ValidationError

from pipeline.errors import InputFileError
from pipeline.io.las.header import Header, Item, header_number
from pipeline.uncertainty.tieon import TieOn, TieOnRecord

__all__ = ["read_tie_on", "tie_on_items"]

_ITEM = re.compile(r"TIE(MD|BASIS|SURVEY|PARENT|SEMI)([0-9]+)")
_FIELDS = {
    "MD": "md",
    "BASIS": "basis",
    "SURVEY": "survey",
    "PARENT": "parent",
    "SEMI": "semi_major",
}
"""The TieOn field of each item's key."""
_LENGTHS = ("MD", "SEMI")


def tie_on_items(record: TieOnRecord, with_survey: bool) -> list[tuple[str, str, str | float, str]]:
    """The ~Parameter items (mnemonic, unit, value, description) of ``record``; survey ids
    where ``with_survey`` (the survey curve is written: the reader takes its ids from it).
    ``ValueError`` for a survey id a LAS value cannot hold (a colon, a line break)."""
    items: list[tuple[str, str, str | float, str]] = []
    for k, tie in enumerate(record.surveys, start=1):
        of = f"survey {k}'s"
        items.append((f"TIEMD{k}", "m", tie.md, f"MD of {of} tie-on, where its uncertainty starts"))
        basis = f"{of} tie-on uncertainty (wellhead, survey, given, not included)"
        items.append((f"TIEBASIS{k}", "", tie.basis, basis))
        named = [
            ("SURVEY", tie.survey if with_survey else None, f"id of survey {k}"),
            ("PARENT", tie.parent, f"the survey that survey {k} is tied on"),
        ]
        for key, value, words in named:
            if value is None:
                continue
            if ":" in value or "\n" in value or "\r" in value:
                raise ValueError(f"survey id {value!r} cannot be a LAS value (a colon, a break)")
            items.append((f"TIE{key}{k}", "", value, words))
        if tie.semi_major is not None:
            items.append(
                (f"TIESEMI{k}", "m", tie.semi_major, f"{of} given tie-on semi-major axis, 1 sigma")
            )
    return items


def read_tie_on(path: Path, header: Header) -> TieOnRecord | None:
    """The tie-on record the header's ``TIE…k`` items state (None: none does);
    :class:`InputFileError` at the line of an item that is not as :func:`tie_on_items`
    writes it (a length not in m, a basis no tie-on has, survey ``k`` without its MD or
    basis, a gap in the numbering)."""
    found: dict[int, dict[str, Item]] = {}
    for item in header.well + header.parameters:
        match = _ITEM.fullmatch(item.mnemonic)
        if match is None or not item.value:
            continue
        same = found.setdefault(int(match[2]), {})
        if match[1] in same and same[match[1]].value != item.value:
            first = same[match[1]]
            raise InputFileError(
                path,
                f"{item.mnemonic} is given twice with different values ({first.value!r} on "
                f"line {first.line}, {item.value!r})",
                line=item.line,
            )
        same[match[1]] = item
    if not found:
        return None
    surveys = []
    for k in range(1, max(found) + 1):
        items = found.get(k, {})
        missing = [f"TIE{key}{k}" for key in ("MD", "BASIS") if key not in items]
        if missing:
            near = items or found[min(j for j in found if j > k)]
            raise InputFileError(
                path,
                f"{' and '.join(missing)} missing: the tie-on of each survey 1…{max(found)} "
                "states its MD and basis",
                line=min(i.line for i in near.values()),
            )
        values: dict[str, object] = {}
        for key, item in items.items():
            if key in _LENGTHS and item.unit.lower() != "m":
                unit = item.unit or "no unit"
                raise InputFileError(
                    path, f"{item.mnemonic} in {unit!r}: expected m", line=item.line
                )
            values[_FIELDS[key]] = header_number(path, item) if key in _LENGTHS else item.value
        try:
            surveys.append(TieOn.model_validate(values))
        except ValidationError as exc:
            error = exc.errors()[0]
            key = next((k for k, f in _FIELDS.items() if error["loc"][:1] == (f,)), "BASIS")
            where = items[key]
            raise InputFileError(
                path, f"{where.mnemonic} {where.value!r}: {error['msg']}", line=where.line
            ) from None
    return TieOnRecord(surveys=tuple(surveys))
