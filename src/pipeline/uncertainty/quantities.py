"""The named quantities a tool model's weighting functions read: the survey's stations, the
site (latitude, geomagnetic field, gravity) and the model's own parameters.

Names (units): survey ``md``, ``tvd``, ``dmd`` (course length into each station, 0 at the
first) in m, ``inc``, ``azi`` (true), ``azm`` (magnetic: azi − declination) in rad; site
``latitude``, ``dip``, ``declination`` in rad, ``b_total``, ``b_horiz`` (B cos dip) in nT,
``g`` in m/s², ``earth_rate`` (WGS84 Ω) and ``omega_h`` (Ω cos latitude) in rad/h; and each
model parameter by its name, in SI (see :mod:`pipeline.uncertainty.toolmodel`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.site import MagneticReference
from pipeline.errors import GyropipeError
from pipeline.uncertainty.terms import STANDARD_G, Survey, previous

__all__ = [
    "EARTH_RATE_RAD_H",
    "MAGNETIC_NAMES",
    "SITE_NAMES",
    "SURVEY_NAMES",
    "MissingSiteQuantity",
    "ModelSite",
    "Quantities",
]

FloatArray = NDArray[np.float64]

EARTH_RATE_RAD_H = 7.292115e-5 * 3600.0
"""Earth rotation rate, rad/h (WGS84)."""

SURVEY_NAMES = frozenset({"md", "tvd", "dmd", "inc", "azi"})
MAGNETIC_NAMES = frozenset({"azm", "dip", "declination", "b_total", "b_horiz"})
LATITUDE_NAMES = frozenset({"latitude", "omega_h"})
SITE_NAMES = MAGNETIC_NAMES | LATITUDE_NAMES | {"g", "earth_rate"}
"""Every name of a site quantity (the magnetic ones need the field, the latitude ones the
latitude)."""


class MissingSiteQuantity(GyropipeError, ValueError):
    """A tool model needs a site quantity (latitude, geomagnetic field) that was not given."""


@dataclass(frozen=True)
class ModelSite:
    """Where a survey was run, as the error models need it: latitude (deg, gyro models),
    the geomagnetic reference (magnetic models) and gravity G (m/s²)."""

    latitude: float | None = None
    magnetic: MagneticReference | None = None
    g: float = STANDARD_G


@dataclass(frozen=True)
class Quantities:
    """The named quantities of one survey at one site under one model's parameters (SI)."""

    survey: Survey
    site: ModelSite
    parameters: Mapping[str, float] = field(default_factory=dict)
    model: str = "tool model"

    @property
    def n(self) -> int:
        return self.survey.size

    @property
    def md(self) -> FloatArray:
        return self.survey.md

    @property
    def inc(self) -> FloatArray:
        return self.survey.inc

    @property
    def azi(self) -> FloatArray:
        return self.survey.azi

    @property
    def tvd(self) -> FloatArray:
        return self.survey.tvd

    @cached_property
    def dmd(self) -> FloatArray:
        return self.survey.md - previous(self.survey.md)

    @property
    def g(self) -> float:
        return self.site.g

    @property
    def earth_rate(self) -> float:
        return EARTH_RATE_RAD_H

    @property
    def latitude(self) -> float:
        if self.site.latitude is None:
            raise MissingSiteQuantity(f"{self.model} needs the site's latitude")
        return float(np.radians(self.site.latitude))

    @property
    def omega_h(self) -> float:
        """Horizontal Earth rate Ω cos φ, rad/h."""
        if self.site.latitude is None:
            raise MissingSiteQuantity(f"{self.model} needs the site's latitude")
        return float(EARTH_RATE_RAD_H * np.cos(np.radians(self.site.latitude)))

    def _field(self) -> MagneticReference:
        if self.site.magnetic is None:
            raise MissingSiteQuantity(
                f"{self.model} needs the site's geomagnetic field (total field, dip, declination)"
            )
        return self.site.magnetic

    @property
    def dip(self) -> float:
        return float(np.radians(self._field().dip))

    @property
    def tan_dip(self) -> float:
        return float(np.tan(np.radians(self._field().dip)))

    @property
    def declination(self) -> float:
        return float(np.radians(self._field().declination))

    @property
    def b_total(self) -> float:
        return float(self._field().total_field)

    @property
    def b_horiz(self) -> float:
        """Horizontal field B cos dip, nT."""
        m = self._field()
        return float(m.total_field * np.cos(np.radians(m.dip)))

    @cached_property
    def azm(self) -> FloatArray:
        """Magnetic azimuth A − declination, rad."""
        return self.survey.azi - self.declination

    def parameter(self, name: str) -> float:
        """A model parameter (SI); a weighting function that needs one names it."""
        if name not in self.parameters:
            raise MissingSiteQuantity(f"{self.model} gives no parameter {name!r}")
        return float(self.parameters[name])

    def __getitem__(self, name: str) -> FloatArray | float:
        """A quantity by name (for formulas): survey, site or model parameter."""
        if name in SURVEY_NAMES or name in SITE_NAMES:
            value: FloatArray | float = getattr(self, name)
            return value
        return self.parameter(name)
