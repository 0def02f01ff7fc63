"""What a tool at rest at the site should measure: Earth rate, latitude, normal gravity and,
for magnetometers, the geomagnetic field."""

from __future__ import annotations

from dataclasses import dataclass

from pipeline.earth.geomagnetic import ModelKey, reference_field
from pipeline.earth.site import MagneticReference, Site
from pipeline.gyrocompass.precision import OMEGA_DEG_H
from pipeline.qc.options import QcInputError


@dataclass(frozen=True)
class EarthReference:
    """What a tool at rest at the site should measure."""

    rate: float
    """Ω, °/h"""
    latitude: float
    """φ, deg"""
    gravity: float
    """normal gravity at the wellhead, m/s²"""
    magnetic: MagneticReference | None
    """reference field (total field nT, dip deg), when magnetometers are checked"""


def earth_reference(site: Site, *, magnetic: bool, model: ModelKey = "wmm2025") -> EarthReference:
    """References at ``site``; with ``magnetic``, the site's field or else ``model`` at the
    wellhead and survey date (raises :class:`~pipeline.earth.geomagnetic.ModelValidityError`
    for a date outside the model). Gravity and field are the wellhead's: at a few km depth
    gravity changes by < 1e-5 m/s² and the main field by ~0.03 nT/m, both well inside the
    default tolerances."""
    reference = None
    if magnetic:
        reference = site.magnetic
        if reference is None:
            if site.date is None:
                raise QcInputError("magnetometer checks need the survey date (field model)")
            reference = reference_field(
                site.latitude, site.longitude, site.elevation, site.date, model=model
            ).reference()
    return EarthReference(OMEGA_DEG_H, site.latitude, site.gravity, reference)
