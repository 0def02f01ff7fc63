"""The ISCWSA gyro error models (SPE 90408; OWSG GYRO-NS, GYRO-NS-CT, GYRO-MWD) through their
tool-model files, and the two changes a measured survey makes to them.

The models are data (``models/gyro-*.yaml``, read by :mod:`pipeline.uncertainty.engine`); the
weighting functions are in :mod:`pipeline.uncertainty.weightfns` (gyro rate terms divide by
the horizontal Earth rate Ω cos φ: the gyrocompass azimuth error of a bias b is b/(Ω cos φ);
the continuous drift and random walk of GYRO-NS-CT accumulate along the hole at the running
speed above the static end inclination, SPE 90408 Table 7).

- :func:`with_initial_azimuth`: when the initial azimuth error of a continuous run is
  measured (its compassed stop's σ), that one systematic azimuth error replaces the
  stationary gyro terms (SPE 90408's initialisation error carried through the continuous
  section) and the continuous section starts at the first station.
- :func:`with_measured_noise`: GXY-RN set from a measured compassing azimuth scatter.

:class:`GyroTool` and :func:`gyro_terms`/:func:`gyro_covariance` keep the earlier Python API:
a tool is a model name plus magnitudes (in the sheet's units) and parameters that override
the file's.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np
from numpy.typing import NDArray

from pipeline.errors import Location
from pipeline.uncertainty.engine import configure, find_model, term_covariances
from pipeline.uncertainty.quantities import EARTH_RATE_RAD_H, ModelSite, Quantities
from pipeline.uncertainty.terms import STANDARD_G, Survey, Term
from pipeline.uncertainty.toolmodel import ToolModel, ToolTerm
from pipeline.uncertainty.weightfns import WEIGHT_FUNCTIONS

__all__ = [
    "EARTH_RATE_RAD_H",
    "GYRO_PRESETS",
    "STATIONARY_GYRO_CODES",
    "GyroTool",
    "gyro_covariance",
    "gyro_terms",
    "with_initial_azimuth",
    "with_measured_noise",
]

FloatArray = NDArray[np.float64]

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
    σ_A = f·RN/(Ω cos φ) (f the noise reduction), so RN = σ_A·Ω cos φ/f (deg/h)."""
    rate_deg_h = np.degrees(EARTH_RATE_RAD_H) * np.cos(np.radians(latitude_deg))
    f = model.parameters.get("noise_reduction", 1.0)
    rn = np.radians(sigma_azi_deg) * rate_deg_h / f
    term = model.term("GXY-RN")
    return replace(
        model,
        terms=tuple(
            replace(t, magnitude=float(rn), unit="deg/h") if t is term else t for t in model.terms
        ),
    )


@dataclass(frozen=True)
class GyroTool:
    """A gyro tool model: a model file (``model``; default GYRO-NS, GYRO-NS-CT when
    ``continuous``) with magnitudes (the sheet's units: deg, deg/h, deg/h/g, deg/√h, m/s², m,
    -) and parameters overriding the file's where given (None keeps the file's).

    ``gxy_b1``/``gxy_b2`` set GXY-B1R/B2R (GXY-B1S/B2S in a continuous model);
    ``init_sigma_azi`` applies :func:`with_initial_azimuth`; ``include_xcl=False`` drops
    XCLA/XCLH."""

    model: str | None = None
    continuous: bool = False
    include_xcl: bool = True
    init_sigma_azi: float | None = None  # deg, measured initial azimuth σ (continuous)
    drfr: float | None = None  # m
    dsfs: float | None = None  # -
    dstg: float | None = None  # 1/m
    sage: float | None = None  # deg
    xym1: float | None = None  # deg
    xym2: float | None = None  # deg
    xym3e: float | None = None  # deg
    xym4e: float | None = None  # deg
    axyz_mis: float | None = None  # deg
    axyz_sf: float | None = None  # -
    axyz_zb: float | None = None  # m/s²
    gxy_b1: float | None = None  # deg/h
    gxy_b2: float | None = None  # deg/h
    gxy_g1: float | None = None  # deg/h/g
    gxy_g4: float | None = None  # deg/h/g
    gxy_rn: float | None = None  # deg/h
    gxy_gd: float | None = None  # deg/h (continuous)
    gxy_grw: float | None = None  # deg/√h (continuous)
    xcla: float | None = None  # -
    xclh: float | None = None  # -
    noise_reduction: float | None = None  # -
    running_speed: float | None = None  # m/h (continuous)
    static_end_inc: float | None = None  # deg (continuous); < 0: from station 0
    xcl_tortuosity: float | None = None  # rad/m
    extra: dict[str, float] = field(default_factory=dict)  # more magnitudes, by term name

    def with_measured_noise(self, sigma_azi_deg: float, latitude_deg: float) -> GyroTool:
        """A copy whose GXY-RN reproduces a measured compassing azimuth scatter
        (:func:`with_measured_noise`)."""
        rn = with_measured_noise(self.tool_model(), sigma_azi_deg, latitude_deg).term("GXY-RN")
        return replace(self, gxy_rn=rn.magnitude)

    def tool_model(self) -> ToolModel:
        """The model file with this tool's changes."""
        model = configure(
            self.model or ("GYRO-NS-CT" if self.continuous else "GYRO-NS"), self._overrides()
        )
        if not self.include_xcl:
            xcl = tuple(t for t in model.terms if not t.name.startswith("XCL"))
            model = replace(model, terms=xcl)
        if self.init_sigma_azi is not None:
            model = with_initial_azimuth(model, self.init_sigma_azi)
        return model

    def _overrides(self) -> dict[str, float]:
        skip = {"model", "continuous", "include_xcl", "init_sigma_azi", "extra"}
        out = {
            f.name: float(getattr(self, f.name))
            for f in fields(self)
            if f.name not in skip and getattr(self, f.name) is not None
        }
        out.update(self.extra)
        return out


GYRO_PRESETS: dict[str, GyroTool] = {
    name: GyroTool(model=name, continuous=name == "GYRO-NS-CT")
    for name in ("GYRO-NS", "GYRO-NS-noXCL", "GYRO-NS-CT", "GYRO-MWD")
}
"""Named gyro tool models (OWSG short names; each a model file)."""


def gyro_terms(
    tool: GyroTool | str | ToolModel, latitude_deg: float, *, g: float = STANDARD_G
) -> list[Term]:
    """The terms of a gyro model at a latitude, magnitudes in SI (m, rad, rad/h…)."""
    model = tool.tool_model() if isinstance(tool, GyroTool) else find_model(tool)
    site = ModelSite(latitude=latitude_deg, g=g)
    return model.terms_for(lambda s: Quantities(s, site, model.parameters, model.name))


def gyro_covariance(
    survey: Survey,
    latitude_deg: float,
    tool: GyroTool | str | ToolModel = "GYRO-NS",
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    g: float = STANDARD_G,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) of a survey and the term names."""
    model = tool.tool_model() if isinstance(tool, GyroTool) else find_model(tool)
    return term_covariances(
        survey, model, ModelSite(latitude=latitude_deg, g=g), basis=basis, surface_tie=surface_tie
    )
