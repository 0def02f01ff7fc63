"""Each well's position covariance from its tool model, by the model's name.

One function, :func:`well_covariance`, gives the NEV covariance (n, 3, 3) of a well's
stations under a named ISCWSA tool model, all terms summed (Williamson, SPE 67616), with the
models' defaults (balanced-tangent Jacobians, the surface tie-on). The models are the gyro
and MWD Rev 5 presets and the tool-model files (:func:`pipeline.uncertainty.model_files`,
e.g. ``ISCWSA-MWD-REV4``); names are case-insensitive. A clearance scan needs nothing else
of the error models.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pipeline.survey.stations import defined_azimuths
from pipeline.uncertainty.engine import covariance, find_model, model_files
from pipeline.uncertainty.gyro import GYRO_PRESETS, gyro_covariance
from pipeline.uncertainty.mwd import MWD_PRESETS, mwd_covariance
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.terms import Survey

__all__ = ["ModelSite", "model_names", "needs", "resolve_model", "well_covariance"]

FloatArray = NDArray[np.float64]


def model_names() -> list[str]:
    """The tool models a well may name (canonical spelling)."""
    return [*GYRO_PRESETS, *MWD_PRESETS, *model_files()]


def resolve_model(name: str) -> str:
    """The canonical spelling of a model name given in any case (ValueError: unknown)."""
    for known in model_names():
        if known.casefold() == name.strip().casefold():
            return known
    raise ValueError(f"unknown tool model {name!r}; expected one of {model_names()}")


def needs(model: str) -> frozenset[str]:
    """What a model needs of the site: ``latitude`` and/or ``magnetic``."""
    if model in GYRO_PRESETS:
        return frozenset({"latitude"})
    if model in MWD_PRESETS:
        return frozenset({"magnetic"})
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
    name = resolve_model(model)
    if name in GYRO_PRESETS:
        if site.latitude is None:
            raise ValueError(f"model {name!r} needs the latitude")
        terms = gyro_covariance(survey, site.latitude, name, g=site.g)[1]
    elif name in MWD_PRESETS:
        if site.magnetic is None:
            raise ValueError(f"model {name!r} needs the geomagnetic reference")
        terms = mwd_covariance(survey, site.magnetic, name, g=site.g)[1]
    else:
        return covariance(survey, name, site)
    out: FloatArray = terms.sum(axis=0)
    return out
