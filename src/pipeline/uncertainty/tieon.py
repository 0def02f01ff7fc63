"""Where a survey's position uncertainty starts: the uncertainty of its tie-on position.

Each survey's covariances are propagated down from its first station. A survey tied on
another survey of the table (a sidetrack's main bore, the run it continues) is propagated
from the wellhead through that survey's stations (the position-uncertainty stage's hole
paths), so the hole above it is in its σ. A survey whose first station lies below the depth
reference (MD > :data:`AT_REFERENCE_M`) and is tied on a position from outside the run — its
stations file's listing, the pipeline's tie (TVD = MD, N = E = 0 by default) — starts from
that position as if it were exactly known: the uncertainty of the surveys above it is not the
run's to know.
It is added where given (:class:`TieCovariance`: e.g. the previous survey's covariance at
that MD, as its listing states), else recorded as not included, which every deliverable that
states the uncertainty then says (:class:`TieOn`). Lengths m, covariances m² (NEV).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Literal

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from pipeline.errors import SurveyCheckWarning
from pipeline.uncertainty.ellipse import ellipses

__all__ = [
    "TIE_COVARIANCE",
    "TIE_ON_KEY",
    "TieCovariance",
    "TieOn",
    "TieOnRecord",
    "outside_ties",
    "tie_on_of",
    "warn_missing",
    "with_tie_on",
]

AT_REFERENCE_M = 1.0
"""A first station this close to MD 0 (m) starts at the depth reference: the hole above it,
under a metre, moves it by millimetres for any plausible angle error (1° over 1 m: 17 mm,
within the ISCWSA surface tie-on allowance) — a point survey's first stop reads an MD of a
few millimetres from the odometer's noise."""
TIE_ON_KEY = b"gyropipe.uncertainty_tie_on"
"""Schema metadata: the :class:`TieOnRecord` of a trajectory's uncertainty columns."""

TieBasis = Literal["wellhead", "survey", "given", "not included"]


class TieCovariance(BaseModel):
    """NEV covariance (1σ², m²) of a tie-on position: the uncertainty of the hole above it."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    nn: float = Field(ge=0, description="north variance, m²")
    ne: float = Field(0.0, description="north-east covariance, m²")
    nv: float = Field(0.0, description="north-vertical covariance, m²")
    ee: float = Field(ge=0, description="east variance, m²")
    ev: float = Field(0.0, description="east-vertical covariance, m²")
    vv: float = Field(ge=0, description="vertical variance, m²")

    @model_validator(mode="after")
    def _positive_semidefinite(self) -> TieCovariance:
        matrix = self.matrix()
        least = float(np.linalg.eigvalsh(matrix).min())
        if least < -1e-12 * max(float(np.abs(matrix).max()), 1.0):
            raise ValueError(
                f"not a covariance: its smallest eigenvalue is {least:.3g} m² (a covariance "
                "has none below 0; check the signs and the off-diagonal entries)"
            )
        return self

    def matrix(self) -> NDArray[np.float64]:
        """The 3×3 NEV covariance, m²."""
        return np.array(
            [[self.nn, self.ne, self.nv], [self.ne, self.ee, self.ev], [self.nv, self.ev, self.vv]]
        )

    def semi_major(self) -> float:
        """The horizontal error ellipse's semi-major axis, 1σ, m."""
        nn, ne, ee, vv = (np.array([v]) for v in (self.nn, self.ne, self.ee, self.vv))
        return float(ellipses(nn, ne, ee, vv).semi_major[0])


TIE_COVARIANCE = (
    "NEV covariance (1σ², m²: nn, ne, nv, ee, ev, vv; N and E referred to the north of the "
    "listing's azimuths, as its covariance columns are) of the tie-on position of the survey "
    "that starts below the depth reference (MD > 1 m) tied on a position from outside the "
    "run (its stations file's listing, the tie parameters): the uncertainty of the hole "
    "above it, e.g. the previous survey's at that MD; added to its every station (and to "
    "those of surveys tied on it). Default: not included, which the deliverables and a warning say"
)
"""The ``tie_covariance`` parameter of the stages that propagate position uncertainty."""


class TieOn(BaseModel):
    """Where one survey's uncertainty starts and whether the tie-on's own is in it:
    ``wellhead`` (its first station within :data:`AT_REFERENCE_M` of MD 0: nothing above),
    ``survey`` (propagated through ``parent`` above it), ``given`` (the run was given it,
    ``semi_major`` its horizontal semi-major axis at 1σ, m), ``not included`` (taken as
    exactly known)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    survey: str | None = Field(None, description="survey id (None: the table's one survey)")
    md: float = Field(description="MD of the survey's first station, m")
    basis: TieBasis
    parent: str | None = Field(None, description="basis 'survey': the survey it is tied on")
    semi_major: float | None = Field(
        None,
        ge=0,
        description="basis 'given': horizontal semi-major axis of the given covariance, 1σ, m",
    )

    @model_validator(mode="after")
    def _consistent(self) -> TieOn:
        """A tie-on as :func:`outside_ties` and the uncertainty stage make them: a parent
        with basis ``survey`` only, a size with ``given`` only, ``wellhead`` at the depth
        reference only (a file stating otherwise states another tie-on than its own)."""
        if (self.parent is None) == (self.basis == "survey"):
            raise ValueError(
                f"basis {self.basis!r} with parent {self.parent!r}: a parent "
                "survey goes with basis 'survey', and only with it"
            )
        if self.semi_major is not None and self.basis != "given":
            raise ValueError(
                f"basis {self.basis!r} with a semi_major: only a given tie-on "
                "uncertainty has a size"
            )
        if self.basis == "wellhead" and _below_reference(self.md):
            raise ValueError(
                f"basis 'wellhead' at MD {self.md:.2f} m: the wellhead tie-on "
                f"is within {AT_REFERENCE_M:g} m of MD 0"
            )
        return self

    def missing(self) -> bool:
        """The tie-on lies below the depth reference and its uncertainty is not in the σ."""
        return self.basis == "not included"

    def words(self) -> str:
        """The tie-on's uncertainty in words (lengths m), or '' at the wellhead."""
        where = f"its tie-on at {self.md:.2f} m MD"
        if self.basis == "not included":
            said = (
                f"the position uncertainty is propagated from {where}, taken as exactly known: "
                "the uncertainty of the tie-on position (of the hole above it) is not included."
            )
        elif self.basis == "given":
            size = f" ({self.semi_major:.3g} m semi-major axis at 1σ)" if self.semi_major else ""
            said = f"the position uncertainty includes the given uncertainty of {where}{size}."
        elif self.basis == "survey":
            said = f"the position uncertainty carries survey {self.parent}'s down to {where}."
        else:
            return ""
        return (
            f"Survey {self.survey}: {said}"
            if self.survey is not None
            else said[0].upper() + said[1:]
        )


class TieOnRecord(BaseModel):
    """The :class:`TieOn` of each survey of a trajectory, in its order."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    surveys: tuple[TieOn, ...]


def _below_reference(md: float) -> bool:
    """A first station at ``md`` (m) lies below the depth reference (:data:`AT_REFERENCE_M`)."""
    return md > AT_REFERENCE_M


def outside_ties(
    firsts: Sequence[tuple[str | None, float]], given: TieCovariance | None
) -> tuple[TieOn, ...]:
    """The :class:`TieOn` of each survey not tied on another of its table, by its name and
    first station's MD (m): at the wellhead (within :data:`AT_REFERENCE_M` of MD 0), else
    ``given`` or not included. ``given`` is the tie-on of one survey: ``ValueError`` unless
    exactly one starts below the depth reference (which would it be?)."""
    below = [md for _, md in firsts if _below_reference(md)]
    if given is not None and len(below) != 1:
        found = "none does" if not below else f"{len(below)} do"
        raise ValueError(
            "tie_covariance is the tie-on uncertainty of the one survey tied on a position "
            f"below the depth reference from outside the run; {found}"
        )
    return tuple(
        TieOn(survey=survey, md=md, basis="wellhead")
        if not _below_reference(md)
        else TieOn(survey=survey, md=md, basis="given", semi_major=given.semi_major())
        if given is not None
        else TieOn(survey=survey, md=md, basis="not included")
        for survey, md in firsts
    )


GIVE_IT = "Give it as tie_covariance (NEV, m²), e.g. the covariance of the survey above at that MD"
"""What :func:`warn_missing` advises by default."""


def warn_missing(record: TieOnRecord, stage_id: str, advice: str = GIVE_IT) -> None:
    """Warn of each survey whose tie-on's uncertainty is not included, with ``advice``."""
    for tie in record.surveys:
        if tie.missing():
            warnings.warn(
                f"stage {stage_id!r}: {tie.words()} {advice}",
                SurveyCheckWarning,
                stacklevel=3,
            )


def with_tie_on(table: pa.Table, record: TieOnRecord) -> pa.Table:
    """``table`` with ``record`` in its schema metadata (:data:`TIE_ON_KEY`)."""
    meta = dict(table.schema.metadata or {})
    meta[TIE_ON_KEY] = record.model_dump_json().encode()
    return table.replace_schema_metadata(meta)


def tie_on_of(table: pa.Table) -> TieOnRecord | None:
    """The :class:`TieOnRecord` of a trajectory's uncertainty columns, if recorded."""
    raw = (table.schema.metadata or {}).get(TIE_ON_KEY)
    return None if raw is None else TieOnRecord.model_validate_json(raw)
