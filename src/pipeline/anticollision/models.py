"""Each well's position covariance from its tool model, by the model's name.

One function, :func:`well_covariance`, gives the NEV covariance (n, 3, 3) of a well's
stations under a named ISCWSA tool model, all terms summed (Williamson, SPE 67616), with the
models' defaults (balanced-tangent Jacobians, the Rev 5 surface tie-on). A clearance scan
needs nothing else of the error models.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.site import MagneticReference
from pipeline.survey.stations import defined_azimuths
from pipeline.uncertainty.gyro import GYRO_PRESETS, gyro_covariance
from pipeline.uncertainty.mwd import MWD_PRESETS, mwd_covariance
from pipeline.uncertainty.terms import Survey

__all__ = ["MODELS", "ModelSite", "is_magnetic", "well_covariance"]

FloatArray = NDArray[np.float64]

MODELS: tuple[str, ...] = (*GYRO_PRESETS, *MWD_PRESETS)
"""The tool models a well may name."""


@dataclass(frozen=True)
class ModelSite:
    """What the models need of the site: latitude (deg; gyro models) and the geomagnetic
    reference (MWD models)."""

    latitude: float | None = None
    magnetic: MagneticReference | None = None


def is_magnetic(model: str) -> bool:
    """True for a magnetic (MWD) model, which needs the geomagnetic reference."""
    return model in MWD_PRESETS


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
    if model in GYRO_PRESETS:
        if site.latitude is None:
            raise ValueError(f"model {model!r} needs the latitude")
        _, cov = gyro_covariance(survey, site.latitude, model)
    elif model in MWD_PRESETS:
        if site.magnetic is None:
            raise ValueError(f"model {model!r} needs the geomagnetic reference")
        _, cov = mwd_covariance(survey, site.magnetic, model)
    else:
        raise ValueError(f"unknown tool model {model!r}; expected one of {list(MODELS)}")
    out: FloatArray = cov.sum(axis=0)
    return out
