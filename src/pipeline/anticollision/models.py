"""Each well's position covariance from its tool model, by the model's name.

One function, :func:`well_covariance`, gives the NEV covariance (n, 3, 3) of a well's
stations under a named ISCWSA tool model, all terms summed (Williamson, SPE 67616), with the
models' defaults (balanced-tangent Jacobians, the surface tie-on). The models are the
tool-model files (:func:`pipeline.uncertainty.model_files`: the shipped ``GYRO-NS``,
``ISCWSA-MWD-REV4``, … and those plugins add); names are case-insensitive. A clearance
scan needs nothing else of the error models.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pipeline.survey.stations import defined_azimuths
from pipeline.uncertainty.engine import covariance, find_model, model_files
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.terms import Survey

__all__ = ["ModelSite", "model_names", "needs", "resolve_model", "well_covariance"]

FloatArray = NDArray[np.float64]


def model_names() -> list[str]:
    """The tool models a well may name (canonical spelling)."""
    return list(model_files())


def resolve_model(name: str) -> str:
    """The canonical spelling of a model name given in any case (ValueError: unknown)."""
    for known in model_names():
        if known.casefold() == name.strip().casefold():
            return known
    raise ValueError(f"unknown tool model {name!r}; expected one of {model_names()}")


def needs(model: str) -> frozenset[str]:
    """What a model needs of the site: ``latitude`` and/or ``magnetic``."""
    return find_model(model).needs


def well_covariance(
    model: str,
    md: FloatArray,
    inc: FloatArray,
    azi_true: FloatArray,
    tvd: FloatArray,
    site: ModelSite,
) -> FloatArray:
    """NEV covariance (n, 3, 3), m², true north, of one survey's stations (MD, TVD m;
    inclination, true azimuth rad, NaN azimuth at vertical) under tool model ``model``."""
    survey = Survey.of(md, inc, defined_azimuths(azi_true), tvd)
    out: FloatArray = covariance(survey, resolve_model(model), site)
    return out
