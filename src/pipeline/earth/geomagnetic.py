"""Geomagnetic reference field: WMM2025 (through wmm-calculator) and IGRF-14 (through ppigrf).

Inputs are WGS84 geodetic latitude and longitude (deg), height above the ellipsoid (m) and a
UTC date or datetime; arrays broadcast together. Outputs are in the local geodetic NED frame
(north = true north, down = along the ellipsoid normal), in nT, with angles in degrees.

Dates outside a model's validity raise :class:`ModelValidityError`: a model is never
extrapolated. Heights are ellipsoidal: a height above mean sea level differs by the geoid
undulation (tens of metres, about 0.03 nT/m of field change — negligible for survey QC, but
convert when exactness matters).

Both libraries cost 0.2–0.5 s to import, so they are imported on first use.
"""

from __future__ import annotations

import datetime as dt
import importlib
import importlib.metadata
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pipeline.earth.frames import FloatArray
from pipeline.earth.site import MagneticReference
from pipeline.errors import GyropipeError

ModelKey: TypeAlias = Literal["wmm2025", "igrf14"]
DateLike: TypeAlias = (
    dt.date | np.datetime64 | str | Sequence[dt.date | np.datetime64 | str] | NDArray[Any]
)
"""A date or datetime (naive = UTC), an ISO string, or a sequence/array of them."""

BLACKOUT_ZONE_NT = 2000.0
"""WMM military specification: where H < 2000 nT a magnetic compass is unreliable."""
CAUTION_ZONE_NT = 6000.0
"""WMM military specification: where H < 6000 nT compass accuracy may be degraded."""

_POLE_GUARD_DEG = 0.005
"""Latitudes closer than this to a pole are evaluated this far from it, on the given meridian
(≈ 550 m; the field changes by a few nT). ppigrf divides by zero at the poles and
wmm-calculator 1.4.4 evaluates points within 0.0018° of the south pole at the north pole."""

_IGRF_EPOCHS = np.arange(1900.0, 2030.0 + 1.0, 5.0)
"""Knots of IGRF-14 (decimal years): DGRF 1945–2020, IGRF 2025, and 2030 = 2025 + 5·SV."""


class GeomagneticInputError(GyropipeError, ValueError):
    """Invalid input to the geomagnetic reference: latitude, coordinates, date or model name."""


class ModelValidityError(GyropipeError):
    """A date lies outside the validity interval of the field model."""

    def __init__(self, model: FieldModel, date: np.datetime64, count: int) -> None:
        self.model = model
        self.date = date
        self.count = count
        more = f" (and {count - 1} more)" if count > 1 else ""
        super().__init__(
            f"{model.name} is valid from {model.valid_from} to {model.valid_to} (exclusive); "
            f"date {date}{more} is outside it and the model is not extrapolated"
        )


@dataclass(frozen=True)
class FieldModel:
    """A geomagnetic field model and the library that evaluates it.

    ``valid_from ≤ date < valid_to`` (dates as UTC midnight)."""

    key: ModelKey
    name: str
    """model name as recorded with results: ``WMM2025`` or ``IGRF14``"""
    version: str
    """evaluating library and its version, e.g. ``wmm-calculator 1.4.4``"""
    valid_from: dt.date
    valid_to: dt.date


_MODELS: dict[str, tuple[str, str, dt.date, dt.date]] = {
    "wmm2025": ("WMM2025", "wmm-calculator", dt.date(2025, 1, 1), dt.date(2030, 1, 1)),
    "igrf14": ("IGRF14", "ppigrf", dt.date(1900, 1, 1), dt.date(2030, 1, 1)),
}


def field_model(model: ModelKey = "wmm2025") -> FieldModel:
    """Description of ``model`` (``"wmm2025"`` or ``"igrf14"``) with the installed library
    version."""
    if model not in _MODELS:
        raise GeomagneticInputError(
            f"unknown geomagnetic model {model!r}; known: {', '.join(sorted(_MODELS))}"
        )
    name, library, valid_from, valid_to = _MODELS[model]
    try:
        version = importlib.metadata.version(library)
    except importlib.metadata.PackageNotFoundError:
        raise GeomagneticInputError(
            f"{name} needs the {library} package, which is not installed"
        ) from None
    return FieldModel(model, name, f"{library} {version}", valid_from, valid_to)


@dataclass(frozen=True)
class FieldUncertainty:
    """One-sigma model uncertainty (WMM error model): components in nT, angles in deg."""

    north: FloatArray
    east: FloatArray
    down: FloatArray
    horizontal: FloatArray
    total_field: FloatArray
    dip: FloatArray
    declination: FloatArray


_WMM2025_ERROR = {"X": 137.0, "Y": 89.0, "Z": 141.0, "H": 133.0, "F": 138.0, "I": 0.20}
_WMM2025_D_OFFSET_DEG = 0.26
_WMM2025_D_COEF_DEG_NT = 5417.0


@dataclass(frozen=True, eq=False)
class GeomagneticField:
    """Reference field at one or more points (arrays of the broadcast input shape).

    NED components relative to true north and the ellipsoid normal, nT; ``dip`` (inclination)
    in deg, positive down; ``declination`` in deg, positive east of true north. ``horizontal``,
    ``total_field``, ``dip`` and ``declination`` are computed from the components."""

    north: FloatArray
    east: FloatArray
    down: FloatArray
    total_field: FloatArray
    horizontal: FloatArray
    dip: FloatArray
    declination: FloatArray
    model: str
    model_version: str

    @classmethod
    def from_ned(
        cls, north: ArrayLike, east: ArrayLike, down: ArrayLike, model: str, model_version: str
    ) -> GeomagneticField:
        """Field from its NED components (nT), deriving H, F, dip and declination."""
        n, e, d = (np.asarray(v, dtype=float) for v in (north, east, down))
        h = np.hypot(n, e)
        return cls(
            north=n,
            east=e,
            down=d,
            total_field=np.hypot(h, d),
            horizontal=h,
            dip=np.degrees(np.arctan2(d, h)),
            declination=np.degrees(np.arctan2(e, n)),
            model=model,
            model_version=model_version,
        )

    def ned(self) -> FloatArray:
        """Field vectors in NED, nT, shape (..., 3)."""
        return np.stack([self.north, self.east, self.down], axis=-1)

    def reference(self) -> MagneticReference:
        """The site reference (total field, dip, declination) of a single-point field."""
        if self.north.size != 1:
            raise GeomagneticInputError(
                f"reference() needs a single point; this field has shape {self.north.shape}"
            )
        return MagneticReference(
            total_field=float(self.total_field.reshape(())),
            dip=float(self.dip.reshape(())),
            declination=float(self.declination.reshape(())),
        )

    def uncertainty(self) -> FieldUncertainty:
        """One-sigma uncertainty of the model (WMM2025 error model; declination as
        √(0.26² + (5417/H)²) deg — computed here because wmm-calculator 1.4.4 gets it wrong).
        IGRF publishes no error model: raises :class:`GeomagneticInputError` for it."""
        if self.model != "WMM2025":
            raise GeomagneticInputError(f"{self.model} publishes no uncertainty model")
        shape = self.north.shape
        err = {k: np.full(shape, v) for k, v in _WMM2025_ERROR.items()}
        with np.errstate(divide="ignore"):
            decl = np.hypot(_WMM2025_D_OFFSET_DEG, _WMM2025_D_COEF_DEG_NT / self.horizontal)
        return FieldUncertainty(
            north=err["X"],
            east=err["Y"],
            down=err["Z"],
            horizontal=err["H"],
            total_field=err["F"],
            dip=err["I"],
            declination=np.minimum(decl, 180.0),
        )


def decimal_year(date: DateLike) -> FloatArray:
    """Decimal year of dates or datetimes (naive = UTC): year + elapsed fraction of it
    (2027-07-02T12:00 → 2027.5), the convention of the WMM and IGRF software."""
    t = _as_datetime64(date)
    years = t.astype("datetime64[Y]")
    start = years.astype("datetime64[us]")
    length = (years + 1).astype("datetime64[us]") - start
    fraction = (t - start) / length
    out: FloatArray = years.astype(np.int64) + 1970.0 + fraction
    return out


def reference_field(
    latitude_deg: ArrayLike,
    longitude_deg: ArrayLike,
    height_m: ArrayLike,
    date: DateLike,
    *,
    model: ModelKey = "wmm2025",
) -> GeomagneticField:
    """Main geomagnetic field of ``model`` at geodetic points (arrays broadcast together).

    ``latitude_deg`` geodetic (WGS84) in [-90, 90]; ``longitude_deg`` east, any finite value;
    ``height_m`` above the WGS84 ellipsoid; ``date`` a date/datetime (naive = UTC) or array of
    them. The geodetic↔geocentric conversion of position and field is the library's (both use
    WGS84). Raises :class:`ModelValidityError` for dates outside the model's validity and
    :class:`GeomagneticInputError` for invalid coordinates. The library's own warnings (WMM
    altitude range, blackout zone) are silenced: compare ``horizontal`` with
    :data:`BLACKOUT_ZONE_NT` / :data:`CAUTION_ZONE_NT` instead.
    """
    info = field_model(model)
    lat = _floats("latitude", latitude_deg)
    lon = _floats("longitude", longitude_deg)
    h = _floats("height", height_m)
    t = _as_datetime64(date)
    try:
        shape = np.broadcast_shapes(lat.shape, lon.shape, h.shape, t.shape)
    except ValueError as exc:
        raise GeomagneticInputError(f"inputs do not broadcast together: {exc}") from None
    lat, lon, h = (np.broadcast_to(a, shape).ravel() for a in (lat, lon, h))
    t = np.broadcast_to(t, shape).ravel()
    _check_coordinates(lat, lon, h)
    _check_validity(info, t)

    if lat.size == 0:
        empty = np.zeros(shape)
        return GeomagneticField.from_ned(empty, empty, empty, info.name, info.version)
    lat_eval = np.clip(lat, -90.0 + _POLE_GUARD_DEG, 90.0 - _POLE_GUARD_DEG)
    lon_eval = (lon + 180.0) % 360.0 - 180.0
    h_km = h / 1000.0
    years = decimal_year(t)
    if model == "wmm2025":
        north, east, down = _wmm2025(lat_eval, lon_eval, h_km, years)
    else:
        north, east, down = _igrf14(lat_eval, lon_eval, h_km, years)
    return GeomagneticField.from_ned(
        north.reshape(shape), east.reshape(shape), down.reshape(shape), info.name, info.version
    )


def _floats(name: str, value: ArrayLike) -> FloatArray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise GeomagneticInputError(f"{name} must be numeric; got {value!r} ({exc})") from None


def _as_datetime64(date: DateLike) -> NDArray[np.datetime64]:
    if isinstance(date, dt.datetime) and date.tzinfo is not None:
        date = date.astimezone(dt.UTC).replace(tzinfo=None)
    try:
        t = np.asarray(date, dtype="datetime64[us]")
    except (TypeError, ValueError) as exc:
        raise GeomagneticInputError(f"not a date: {date!r} ({exc})") from None
    if np.isnat(t).any():
        raise GeomagneticInputError(f"missing date (NaT) in {date!r}")
    return t


def _check_coordinates(lat: FloatArray, lon: FloatArray, h: FloatArray) -> None:
    for name, values in (("latitude", lat), ("longitude", lon), ("height", h)):
        bad = ~np.isfinite(values)
        if bad.any():
            i = int(np.argmax(bad))
            raise GeomagneticInputError(f"{name} must be finite; got {values[i]} at point {i}")
    bad = np.abs(lat) > 90.0
    if bad.any():
        i = int(np.argmax(bad))
        raise GeomagneticInputError(
            f"latitude must be within [-90, 90] deg; got {lat[i]} at point {i}"
        )


def _check_validity(info: FieldModel, t: NDArray[np.datetime64]) -> None:
    lo = np.datetime64(info.valid_from, "us")
    hi = np.datetime64(info.valid_to, "us")
    bad = (t < lo) | (t >= hi)
    if bad.any():
        first = t[int(np.argmax(bad))]
        shown = first.astype("datetime64[D]") if first == first.astype("datetime64[D]") else first
        raise ModelValidityError(info, shown, int(bad.sum()))


def _wmm2025(
    lat: FloatArray, lon: FloatArray, h_km: FloatArray, years: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    wmm = importlib.import_module("wmm")  # on use: ~0.2 s; untyped

    calc = wmm.wmm_calc()
    unique_years = np.unique(years)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calc.setup_time(dyear=unique_years if unique_years.size == 1 else years)
        calc.setup_env(lat, lon, h_km, unit="km")
        x, y, z = calc.forward_base()
    north, east, down = (np.asarray(v, dtype=float).reshape(lat.shape) for v in (x, y, z))
    return north, east, down


def _igrf14(
    lat: FloatArray, lon: FloatArray, h_km: FloatArray, years: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    ppigrf = importlib.import_module("ppigrf")  # on use: ~0.5 s (pandas); untyped

    shc = Path(str(ppigrf.__file__)).with_name("IGRF14.shc")
    if not shc.is_file():
        raise GeomagneticInputError(f"the installed ppigrf does not ship IGRF14.shc ({shc})")
    # IGRF is linear in time between its 5-yearly knots, and the field is linear in the
    # coefficients: evaluate each point at its two knots and interpolate in decimal years
    # (the IGRF definition), with one library call whatever the number of distinct dates.
    k = np.clip(((years - _IGRF_EPOCHS[0]) // 5.0).astype(int), 0, _IGRF_EPOCHS.size - 2)
    knots = np.unique(np.concatenate([k, k + 1]))
    when = [dt.datetime(int(_IGRF_EPOCHS[i]), 1, 1) for i in knots]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        be, bn, bu = ppigrf.igrf(lon, lat, h_km, when, coeff_fn=str(shc))
    row0 = np.searchsorted(knots, k)
    row1 = np.searchsorted(knots, k + 1)
    col = np.arange(lat.size)
    w = (years - _IGRF_EPOCHS[k]) / 5.0

    def at(b: FloatArray) -> FloatArray:
        out: FloatArray = (1.0 - w) * b[row0, col] + w * b[row1, col]
        return out

    return at(bn), at(be), -at(bu)
