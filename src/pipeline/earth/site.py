"""The survey site: wellhead position, date and the Earth references derived from them; and
where a stage finds it (:func:`resolve_site`)."""

from __future__ import annotations

import datetime as dt
from functools import cached_property

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from pipeline.earth.frames import FloatArray, earth_rate_ned
from pipeline.earth.gravity import normal_gravity
from pipeline.errors import MissingSiteError
from pipeline.well import Latitude, WellMetadata


class MagneticReference(BaseModel):
    """Geomagnetic field at the site (from a reference model such as IGRF or WMM)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    total_field: float = Field(gt=0, description="total field intensity, nT")
    dip: float = Field(ge=-90, le=90, description="dip (inclination) angle, deg, down positive")
    declination: float = Field(
        ge=-180, le=180, description="declination, deg, east of true north positive"
    )

    def ned(self) -> FloatArray:
        """Field vector in NED, nT."""
        dip, dec = np.radians(self.dip), np.radians(self.declination)
        return self.total_field * np.array(
            [np.cos(dip) * np.cos(dec), np.cos(dip) * np.sin(dec), np.sin(dip)]
        )


class Site(BaseModel):
    """Wellhead position (WGS84) and survey date."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    latitude: Latitude = Field(description="geodetic latitude, deg")
    longitude: float = Field(0.0, ge=-180, le=360, description="longitude, deg east")
    elevation: float = Field(0.0, description="height of the wellhead above the ellipsoid, m")
    date: dt.date | None = Field(
        None, description="survey date (needed for a geomagnetic model's field)"
    )
    magnetic: MagneticReference | None = Field(
        None, description="geomagnetic reference at the site (needed for magnetometers)"
    )

    @cached_property
    def gravity(self) -> float:
        """Normal gravity at the wellhead, m/s² (WGS84, Somigliana)."""
        return float(normal_gravity(self.latitude, self.elevation))

    def earth_rate(self) -> FloatArray:
        """Earth rate in NED at the wellhead, rad/s."""
        return earth_rate_ned(np.radians(self.latitude))


class SiteParams(BaseModel):
    """The parameter of a stage that works at the site: its latitude, if not the well's."""

    model_config = ConfigDict(extra="forbid")
    latitude: Latitude | None = Field(
        None, description="site latitude, deg (default: the well metadata's)"
    )


NORTH_SEEKING_LIMIT = 89.9
"""Largest |latitude|, deg, at which a north-seeking gyro is used: nearer a pole the
horizontal Earth rate Ω cos φ it finds north by vanishes."""


def resolve_site(
    well: WellMetadata,
    *,
    stage: str,
    latitude: float | None = None,
    param: str | None = "latitude",
    field: bool = False,
    north_seeking: bool = False,
) -> Site:
    """The site a stage works at. The latitude is the stage's own (``latitude``, from its
    parameter ``param``) when given, else the well's; with ``field`` (a geomagnetic model
    will be evaluated) the well's longitude and survey date are needed too. Whatever else the
    well knows is kept: longitude (else 0), survey date, and its elevation above sea level
    standing in for the ellipsoidal height (else 0; the geoid's tens of metres change
    gravity by < 1e-4 m/s²). Raises :class:`~pipeline.errors.MissingSiteError` naming
    ``stage``, every value missing and where each may be given; with ``north_seeking`` (the
    stage divides by Ω cos φ), a ValueError for a latitude beyond
    ±:data:`NORTH_SEEKING_LIMIT`."""
    if latitude is None:
        latitude = well.latitude
    missing = [
        name
        for name, absent in (
            ("latitude", latitude is None),
            ("longitude", field and well.longitude is None),
            ("survey_date", field and well.survey_date is None),
        )
        if absent
    ]
    if missing:
        raise MissingSiteError(stage, missing, param)
    assert latitude is not None
    if north_seeking and abs(latitude) > NORTH_SEEKING_LIMIT:
        raise ValueError(
            f"latitude {latitude:g}° is beyond ±{NORTH_SEEKING_LIMIT}°: a north-seeking gyro "
            "finds north by the horizontal Earth rate Ω cos φ, which vanishes at the poles"
        )
    return Site(
        latitude=latitude,
        longitude=well.longitude or 0.0,
        elevation=well.elevation or 0.0,
        date=well.survey_date,
    )
