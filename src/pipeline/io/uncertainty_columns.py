"""A trajectory file's uncertainty columns read back as stations carry them: what the file
states of them (a CSV's ``# confidence=``, ``# error_model=`` and ``# tie_on=`` lines, a LAS
file's CONF, ERRMODEL and TIE… items, a WITSML trajectory's ``gyropipe.error_model`` and
``gyropipe.uncertainty_tie_on`` extensions) goes back into their field metadata and the
table's tie-on record (:mod:`pipeline.uncertainty.stated`,
:mod:`pipeline.uncertainty.tieon`), ``ellipse_azimuth`` takes the azimuths' north reference.
A column at a confidence level (``*_conf``) of a file stating none is left out, warned: a
size at an unknown probability must pass for no level, 1σ least of all.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import pyarrow as pa
from pydantic import BaseModel, ValidationError

from pipeline.contracts import NORTH_KEY
from pipeline.errors import InputFileError, warn_input
from pipeline.uncertainty.stated import AT_CONFIDENCE, WORDS, with_statements
from pipeline.uncertainty.tieon import TieOnRecord

UNCERTAINTY_COLUMNS = tuple(WORDS)
"""The uncertainty columns a stations reader carries, by the names gyropipe writes."""
T = TypeVar("T")
R = TypeVar("R", bound=BaseModel)


@dataclass(frozen=True)
class Stated:
    """What a file states of its uncertainty columns (None: nothing)."""

    confidence: float | None = None
    error_model: str | None = None
    tie_on: TieOnRecord | None = None

    @classmethod
    def of(
        cls,
        path: Path,
        confidence: tuple[str, int] | None,
        model: tuple[str, int] | None,
        tie_on: tuple[str, int] | None = None,
    ) -> Stated:
        """The statements of a file, each as its text and line; a confidence that is no
        probability in (0, 1) or a tie-on that is not the record gyropipe writes
        (:func:`tie_on_record`) is an :class:`InputFileError` at its line."""
        level = None
        if confidence is not None:
            text, line = confidence
            try:
                level = float(text)
            except ValueError:
                level = None
            if level is None or not 0.0 < level < 1.0:
                raise InputFileError(
                    path, f"confidence {text!r}: expected a probability in (0, 1)", line=line
                )
        return cls(
            level,
            model[0].strip() or None if model is not None else None,
            None if tie_on is None else tie_on_record(path, *tie_on, TieOnRecord),
        )


def tie_on_record(path: Path, text: str, line: int, model: type[R]) -> R:
    """The tie-on record (``model`` :class:`~pipeline.uncertainty.tieon.TieOnRecord`) or one
    survey's tie-on (:class:`~pipeline.uncertainty.tieon.TieOn`) a file states as JSON, as
    gyropipe's writers write it; an :class:`InputFileError` at ``line`` where it is not one."""
    try:
        return model.model_validate_json(text)
    except ValidationError as exc:
        error = exc.errors()[0]
        where = ".".join(str(p) for p in error["loc"]) or "the value"
        raise InputFileError(
            path,
            f"tie_on {where}: {error['msg']}; expected the tie-on as gyropipe writes it, JSON "
            '{"survey": …, "md": …, "basis": …} (a record: {"surveys": [those]})',
            line=line,
        ) from None


def readable(
    path: Path, chosen: Mapping[str, T], stated: Stated, lines: Mapping[str, int]
) -> dict[str, T]:
    """``chosen`` columns less those at a confidence level when the file states none, each
    warned at its header line (``lines``)."""
    kept = dict(chosen)
    if stated.confidence is not None:
        return kept
    for name in AT_CONFIDENCE:
        if name in kept:
            del kept[name]
            warn_input(
                path,
                f"column {name} left out: the file states no confidence level of it "
                "(CONF, # confidence=), and a size at an unknown level is no 1σ",
                lines.get(name, 0),
            )
    return kept


def stating(table: pa.Table, stated: Stated) -> pa.Table:
    """``table`` whose uncertainty columns state what the file does; ``ellipse_azimuth`` in
    the north reference of ``azi``."""
    if not set(UNCERTAINTY_COLUMNS) & set(table.column_names):
        return table
    table = with_statements(table, stated.confidence, stated.error_model, stated.tie_on)
    if "ellipse_azimuth" not in table.column_names or "azi" not in table.column_names:
        return table
    north = (table.schema.field("azi").metadata or {}).get(NORTH_KEY)
    if north is None:
        return table
    i = table.schema.get_field_index("ellipse_azimuth")
    field = table.schema.field(i)
    return table.set_column(
        i, field.with_metadata({**(field.metadata or {}), NORTH_KEY: north}), table.column(i)
    )
