"""Each well's position covariance from its tool model, by the model's name.

One function, :func:`well_covariance`, gives the NEV covariance (n, 3, 3) of a well's
stations under a named ISCWSA tool model, all terms summed (Williamson, SPE 67616), with the
models' defaults (balanced-tangent Jacobians, the surface tie-on). The models are those of a
:class:`~pipeline.uncertainty.engine.ModelCatalogue` (the shipped tool-model files and those
the run's plugins registered, handed down by the caller; the shipped ones by default);
names are case-insensitive. A clearance scan needs nothing else of the error models.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pipeline.survey.stations import defined_azimuths
from pipeline.uncertainty.engine import (
    SHIPPED,
    ModelCatalogue,
    OutsideValidity,
    covariance,
    find_model,
)
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.terms import Survey

__all__ = ["ModelSite", "needs", "resolve_model", "well_covariance"]

FloatArray = NDArray[np.float64]


def resolve_model(name: str, catalogue: ModelCatalogue = SHIPPED) -> str:
    """The canonical spelling of a model name given in any case (ValueError: unknown)."""
    known = list(catalogue.files())
    for model in known:
        if model.casefold() == name.strip().casefold():
            return model
    raise ValueError(f"unknown tool model {name!r}; expected one of {known}")


def needs(model: str, catalogue: ModelCatalogue = SHIPPED) -> frozenset[str]:
    """What a model needs of the site: ``latitude`` and/or ``magnetic``."""
    return find_model(model, catalogue).needs


def well_covariance(
    model: str,
    md: FloatArray,
    inc: FloatArray,
    azi_true: FloatArray,
    tvd: FloatArray,
    site: ModelSite,
    catalogue: ModelCatalogue = SHIPPED,
    outside_validity: OutsideValidity = "refuse",
) -> FloatArray:
    """NEV covariance (n, 3, 3), m², true north, of one survey's stations (MD, TVD m;
    inclination, true azimuth rad, NaN azimuth at vertical) under tool model ``model``; a
    station outside the model's range refused or, ``outside_validity="flag"``, NaN from it
    down (:func:`pipeline.uncertainty.engine.term_covariances`)."""
    survey = Survey.of(md, inc, defined_azimuths(azi_true), tvd)
    out: FloatArray = covariance(
        survey,
        find_model(resolve_model(model, catalogue), catalogue),
        site,
        outside_validity=outside_validity,
    )
    return out
