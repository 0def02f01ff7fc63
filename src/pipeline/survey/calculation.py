"""How a trajectory's positions were calculated, carried in its Arrow schema metadata.

The stages that integrate stations record the survey calculation method, the azimuth of
the vertical-section plane and where each survey was tied on (:mod:`pipeline.survey.tiein`)
under ``gyropipe.survey_calculation`` (JSON), so exports and the report state them (WITSML
``calcAlgorithm`` and ``aziVertSect``, the LAS ``~Parameter`` section, the JSON summary)
instead of assuming them. Stages that add columns to a trajectory keep the record.
"""

from __future__ import annotations

from typing import TypeVar

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.survey.methods import Method
from pipeline.survey.tiein import SurveyTie

CALCULATION_KEY = b"gyropipe.survey_calculation"
Record = TypeVar("Record", bound=BaseModel)


class SurveyCalculation(BaseModel):
    """The calculation behind a trajectory's positions."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    method: Method = Field(description="survey calculation method")
    vs_azimuth: float = Field(
        description="azimuth of the vertical-section plane, deg, in the azimuths' north "
        "reference; the section's origin is the wellhead"
    )
    ties: tuple[SurveyTie, ...] = Field(
        (),
        description="where each survey's first station was tied (empty: not recorded, a "
        "trajectory computed before ties were)",
    )


def with_record(table: pa.Table, key: bytes, record: BaseModel) -> pa.Table:
    """``table`` with ``record`` (JSON) under ``key`` in its schema metadata."""
    meta = dict(table.schema.metadata or {})
    meta[key] = record.model_dump_json().encode()
    return table.replace_schema_metadata(meta)


def record_of(table: pa.Table, key: bytes, model: type[Record]) -> Record | None:
    """The ``model`` recorded under ``key`` in a table's schema metadata, if any."""
    raw = (table.schema.metadata or {}).get(key)
    return None if raw is None else model.model_validate_json(raw)


def with_calculation(table: pa.Table, calculation: SurveyCalculation) -> pa.Table:
    """``table`` with ``calculation`` recorded in its schema metadata."""
    return with_record(table, CALCULATION_KEY, calculation)


def calculation_of(table: pa.Table) -> SurveyCalculation | None:
    """The calculation recorded in a table's schema metadata, if any."""
    return record_of(table, CALCULATION_KEY, SurveyCalculation)
