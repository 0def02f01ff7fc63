"""The two changes a measured survey makes to an ISCWSA gyro error model (SPE 90408).

The models are data (the gyro tool-model files, read by :mod:`pipeline.uncertainty.engine`);
the weighting functions are in :mod:`pipeline.uncertainty.weightfns` (gyro rate terms divide
by the horizontal Earth rate Ω cos φ: the gyrocompass azimuth error of a bias b is
b/(Ω cos φ); the continuous drift and random walk of a continuous model accumulate along the
hole at the running speed above the static end inclination, SPE 90408 Table 7).

- :func:`with_initial_azimuth`: when the initial azimuth error of a continuous run is
  measured (its compassed stop's σ), that one systematic azimuth error replaces the
  stationary gyro terms (SPE 90408's initialisation error carried through the continuous
  section) and the continuous section starts at the first station.
- :func:`with_measured_noise`: GXY-RN set from a measured compassing azimuth scatter.

Everything else (a model with other magnitudes, its terms, its covariance) is the engine's:
:func:`~pipeline.uncertainty.engine.configure`, :func:`~.engine.model_terms`,
:func:`~.engine.term_covariances`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pipeline.errors import Location
from pipeline.uncertainty.quantities import EARTH_RATE_RAD_H
from pipeline.uncertainty.toolmodel import ToolModel, ToolTerm
from pipeline.uncertainty.weightfns import WEIGHT_FUNCTIONS

__all__ = [
    "EARTH_RATE_RAD_H",
    "STATIONARY_GYRO_CODES",
    "with_initial_azimuth",
    "with_measured_noise",
]

STATIONARY_GYRO_CODES = frozenset({"GXY-B1", "GXY-B2", "GXY-G1", "GXY-G4", "GXY-RN"})
"""Weighting functions of a stationary gyrocompass's xy gyro terms."""


def with_initial_azimuth(model: ToolModel, sigma_deg: float) -> ToolModel:
    """``model`` with its stationary gyro terms replaced by one systematic azimuth error
    ``AZ-INIT`` of ``sigma_deg`` (deg, 1σ) and its continuous section (if any) starting at
    the first station."""
    init = ToolTerm(
        "AZ-INIT",
        ("azi",),
        "systematic",
        float(sigma_deg),
        "deg",
        WEIGHT_FUNCTIONS["AZ"],
        Location(model.file),
        "measured initial azimuth",
    )
    stationary = [k for k, t in enumerate(model.terms) if t.code in STATIONARY_GYRO_CODES]
    at = stationary[0] if stationary else len(model.terms)  # in the place of the first
    kept = [t for k, t in enumerate(model.terms) if k < at and k not in stationary]
    kept += [init] + [t for k, t in enumerate(model.terms) if k >= at and k not in stationary]
    params = dict(model.parameters)
    if "static_end_inc" in params:
        params["static_end_inc"] = -np.inf
    return replace(model, terms=tuple(kept), parameters=params)


def with_measured_noise(model: ToolModel, sigma_azi_deg: float, latitude_deg: float) -> ToolModel:
    """``model`` whose GXY-RN reproduces a measured 1σ compassing azimuth scatter at I = 0:
    σ_A = f·RN/(Ω cos φ) (f the noise reduction), so RN = σ_A·Ω cos φ/f (deg/h) — every
    term of the GXY-RN weighting function (GYRO-NS-CT's GXY-RN-INIT too: the same
    compassing's noise, carried above the static end inclination)."""
    rate_deg_h = np.degrees(EARTH_RATE_RAD_H) * np.cos(np.radians(latitude_deg))
    f = model.parameters.get("noise_reduction", 1.0)
    rn = np.radians(sigma_azi_deg) * rate_deg_h / f
    model.term("GXY-RN")  # a KeyError without one
    return replace(
        model,
        terms=tuple(
            replace(t, magnitude=float(rn), unit="deg/h") if t.code == "GXY-RN" else t
            for t in model.terms
        ),
    )
