"""What a position-uncertainty column states of itself, in its Arrow field metadata (as
units and north references travel, :mod:`pipeline.contracts`), so that every writer can say
it: the error model that made it (:data:`ERROR_MODEL_KEY`) and, for a column at a confidence
level, that level (:data:`CONFIDENCE_KEY`, the probability content) and how the 1σ size was
scaled to it (:data:`DIMENSIONS_KEY`: 2 for the horizontal ellipse, √χ²₂; 1 for the vertical
half-interval, the two-sided normal quantile; :mod:`pipeline.uncertainty.ellipse`); a
description (:data:`~pipeline.contracts.DESCRIPTION_KEY`) says all of it in words.
"""

from __future__ import annotations

import pyarrow as pa

from pipeline.contracts import DESCRIPTION_KEY

__all__ = [
    "CONFIDENCE_KEY",
    "DIMENSIONS_KEY",
    "ERROR_MODEL_KEY",
    "file_statements",
    "model_words",
    "with_statements",
]

CONFIDENCE_KEY = b"gyropipe.confidence"
"""Field metadata: the probability content of a column at a confidence level (``0.95``)."""
DIMENSIONS_KEY = b"gyropipe.confidence_dimensions"
"""Field metadata: the dimensions of that confidence region: ``2`` (an ellipse, χ² of 2 degrees
of freedom) or ``1`` (a two-sided interval of the normal distribution)."""
ERROR_MODEL_KEY = b"gyropipe.error_model"
"""Field metadata: the error model a column was computed with (``GYRO-NS rev 5``)."""

WORDS = {
    "cov_nn": "north variance",
    "cov_ne": "north-east covariance",
    "cov_nv": "north-vertical covariance",
    "cov_ee": "east variance",
    "cov_ev": "east-vertical covariance",
    "cov_vv": "vertical variance",
    "ellipse_major": "semi-major axis of the horizontal error ellipse, 1 sigma",
    "ellipse_minor": "semi-minor axis of the horizontal error ellipse, 1 sigma",
    "ellipse_azimuth": "azimuth of the error ellipse's semi-major axis",
    "sigma_v": "vertical error, 1 sigma",
    "ellipse_major_conf": "semi-major axis of the horizontal error ellipse",
    "ellipse_minor_conf": "semi-minor axis of the horizontal error ellipse",
    "vertical_conf": "vertical error half-interval",
}
"""The uncertainty columns, each described in words (ASCII: a LAS file's descriptions)."""
AT_CONFIDENCE = {"ellipse_major_conf": 2, "ellipse_minor_conf": 2, "vertical_conf": 1}
"""The columns at the confidence level, by the dimensions of their region."""
REGION = {2: "2-D, chi-square of 2 dof", 1: "1-D, two-sided normal"}


def model_words(name: str, revision: str) -> str:
    """An error model as stated: its name and revision (``GYRO-NS rev 5``)."""
    return f"{name} rev {revision}" if revision else name


def with_statements(table: pa.Table, confidence: float, model: str) -> pa.Table:
    """``table`` with its uncertainty columns (:data:`WORDS`) stating ``model``
    (:func:`model_words`), those at a confidence level also ``confidence`` (probability,
    0-1) and their dimensions, and a description of each saying so."""
    fields = []
    for f in table.schema:
        words = WORDS.get(f.name)
        if words is None:
            fields.append(f)
            continue
        meta = {**(f.metadata or {}), ERROR_MODEL_KEY: model.encode()}
        if (dims := AT_CONFIDENCE.get(f.name)) is not None:
            meta[CONFIDENCE_KEY] = repr(confidence).encode()
            meta[DIMENSIONS_KEY] = str(dims).encode()
            words += f" at {confidence * 100:g} % confidence ({REGION[dims]})"
        meta[DESCRIPTION_KEY] = f"{words}; error model {model}".encode()
        fields.append(f.with_metadata(meta))
    return pa.Table.from_arrays(table.columns, schema=pa.schema(fields, table.schema.metadata))


def file_statements(schema: pa.Schema) -> dict[str, str]:
    """What a file of ``schema`` states once for all its columns: ``confidence`` and
    ``error_model`` where its columns state them (empty where none does); ``ValueError``
    where they state different ones (one file, as one north reference, holds one)."""
    stated: dict[str, str] = {}
    for name, key in (("confidence", CONFIDENCE_KEY), ("error_model", ERROR_MODEL_KEY)):
        values = sorted({f.metadata[key].decode() for f in schema if key in (f.metadata or {})})
        if len(values) > 1:
            raise ValueError(f"columns state different {name.replace('_', ' ')}s {values}")
        if values:
            stated[name] = values[0]
    return stated
