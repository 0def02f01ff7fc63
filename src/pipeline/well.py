"""Well metadata: the header that travels with a well's tables.

It is stored as JSON in the Arrow schema metadata under ``gyropipe.well``, so it survives
Parquet files and stage boundaries.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Mapping
from typing import Annotated, Any, Literal

import pyarrow as pa
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    model_serializer,
    model_validator,
)
from pydantic_core.core_schema import SerializerFunctionWrapHandler

from pipeline import jsontext
from pipeline.errors import GyropipeError, ParameterError

WELL_KEY = b"gyropipe.well"


def _yaml_true(value: Any) -> Any:
    """YAML reads an unquoted ``true`` as a boolean; as a north reference it means true north."""
    return "true" if value is True else value


def _no_number(value: Any) -> Any:
    """A date is not a number: pydantic's lax dates read one as a Unix time (``0`` as
    1970-01-01, ``'1772409600'`` as 2026-03-02)."""
    numeric = isinstance(value, str) and re.fullmatch(r"\s*[+-]?\d+(\.\d*)?\s*", value)
    if numeric or (isinstance(value, int | float) and not isinstance(value, bool)):
        raise ValueError(f"{value!r} is a number, not a date (write it as 2026-03-02)")
    return value


SurveyDate = Annotated[dt.date | None, BeforeValidator(_no_number)]
"""A survey date field: a date, never a number read as a Unix time."""
Latitude = Annotated[float, Field(ge=-90, le=90, allow_inf_nan=False)]
"""A geodetic latitude (WGS84), deg, north positive, −90 to 90: the one type of every
latitude (well metadata, site, stage parameters)."""
NorthReference = Annotated[Literal["true", "grid", "magnetic"], BeforeValidator(_yaml_true)]
WELL_DEFAULT = "x-well-default"
"""JSON-schema marker of a reader option whose default is a well metadata field: when the
option is not given, the engine fills it from the run's well metadata (named by the marker)."""
DefaultNorthReference = Annotated[
    NorthReference | None,
    Field(
        description="north reference used only when neither the file nor north_reference "
        "names one (default: the well metadata's north_reference)",
        json_schema_extra={WELL_DEFAULT: "north_reference"},
    ),
]
"""A reader option: the fallback north reference, by default the well metadata's."""
NORTH_WORDS: dict[str, NorthReference] = {
    "true": "true",
    "tn": "true",
    "grid": "grid",
    "gn": "grid",
    "magnetic": "magnetic",
    "mag": "magnetic",
    "mn": "magnetic",
}
"""Words naming a north reference in file headers (``Azimuth Grid``, ``AZI (MN)``, NREF)."""
DATUM_WORDS = {
    "kb": "KB",
    "rkb": "KB",
    "kellybushing": "KB",
    "df": "DF",
    "rdf": "DF",
    "derrickfloor": "DF",
    "gl": "GL",
    "groundlevel": "GL",
}
"""Words (lower case, run together) naming a depth datum in file headers (``RKB``, ``Kelly
Bushing``, LAS DREF), and the datum they name: KB, DF or GL."""


def _angle(description: str) -> Any:
    """An optional north correction field, deg in [-180, 180]."""
    return Field(None, ge=-180, le=180, description=description)


LATER_FIELDS = ("survey_date_last",)
"""Well fields added after digests of pipelines were stored, left out of a dump when None."""


class WellMetadata(BaseModel):
    """Header of one well and survey run. Angles in degrees, lengths in metres."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    well: str | None = Field(None, description="well name")
    wellbore: str | None = Field(
        None, description="wellbore name (a sidetrack's); default: the well's name"
    )
    uwi: str | None = Field(None, description="unique well identifier (UWI/API)")
    field: str | None = Field(None, description="field name")
    company: str | None = Field(None, description="operator")
    service_company: str | None = Field(None, description="survey service company")
    latitude: Latitude | None = Field(None, description="wellhead geodetic latitude, deg (WGS84)")
    longitude: float | None = Field(
        None, ge=-180, le=360, description="wellhead longitude, deg east (WGS84)"
    )
    crs: str | None = Field(
        None, description="coordinate reference system of the map coordinates (EPSG:23031…)"
    )
    easting: float | None = Field(None, description="wellhead map easting in the crs, m")
    northing: float | None = Field(None, description="wellhead map northing in the crs, m")
    elevation: float | None = Field(
        None, description="depth reference elevation above mean sea level, m"
    )
    depth_reference: str | None = Field(
        None, description="depth reference point (RKB, DF, GL, MSL…)"
    )
    survey_date: SurveyDate = Field(
        None, description="date of the survey run (of several trajectories: the first's)"
    )
    survey_date_last: SurveyDate = Field(
        None,
        description="the day the last of the survey's trajectories began, when they began on "
        "several days (survey_date: the first): no one date's geomagnetic field is every "
        "station's",
    )
    tool_type: str | None = Field(None, description="survey tool type")
    tool_preset: str | None = Field(
        None,
        description="the survey tool's entry in the tool catalogue (the simulator's presets: "
        "mems-vrg, dtg-xy, nav-grade…), whose error magnitudes compassing takes as its "
        "default; the simulator sets it",
    )
    tool_name: str | None = Field(None, description="survey tool name (make and model)")
    tool_serial: str | None = Field(None, description="survey tool serial number")
    run_number: str | None = Field(None, description="survey run number")
    job_number: str | None = Field(None, description="service company's job number")
    survey_type: Literal["definitive", "preliminary"] | None = Field(
        None, description="survey status: definitive or preliminary"
    )
    north_reference: NorthReference | None = Field(
        None, description="north reference of the azimuths: true, grid or magnetic"
    )
    declination: float | None = _angle(
        "magnetic declination at the wellhead on the survey date, deg (magnetic north east "
        "of true north positive)"
    )
    grid_convergence: float | None = _angle(
        "grid convergence at the wellhead, deg (grid north east of true north positive)"
    )
    # the geomagnetic reference of the site and date (default: the geomagnetic model's)
    magnetic_field: float | None = Field(None, gt=0, description="geomagnetic total field, nT")
    magnetic_dip: float | None = Field(None, ge=-90, le=90, description="magnetic dip, deg, down +")
    declination_applied: float | None = _angle(
        "magnetic declination already applied to the azimuths, deg (WITSML magDeclUsed: "
        "magnetic azimuths were corrected by it; 0: none applied)"
    )
    grid_convergence_applied: float | None = _angle(
        "grid convergence already applied to the azimuths, deg (WITSML gridCorUsed: true "
        "azimuths were referred to grid north by it; 0: none applied)"
    )

    @model_validator(mode="after")
    def _validated_dates(self) -> WellMetadata:
        """Refuse survey dates out of order (:meth:`_dates_in_order`)."""
        return self._dates_in_order()

    def _dates_in_order(self) -> WellMetadata:
        """This metadata; ``ValueError``: a ``survey_date_last`` before the ``survey_date``."""
        first, last = self.survey_date, self.survey_date_last
        if first is not None and last is not None and last < first:
            raise ValueError(
                f"survey_date_last {last} is before survey_date {first}: the survey's "
                "trajectories began from survey_date to survey_date_last"
            )
        return self

    @model_serializer(mode="wrap")
    def _dumped(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """Every field, but those of :data:`LATER_FIELDS` only when set: the pipeline digest
        (a batch's fingerprint) and the summaries of the wells that lack them stay what they
        were (else every well of a batch would run again, unchanged)."""
        dumped: dict[str, Any] = handler(self)
        for name in LATER_FIELDS:
            if dumped.get(name, 0) is None:
                del dumped[name]
        return dumped

    def convergence_for(self, reference: str) -> float | None:
        """γ (deg) relating azimuths referred to ``reference`` north to true north: for
        grid-north azimuths the convergence applied to them (a WITSML gridCorUsed), else
        the site's ``grid_convergence``."""
        if reference == "grid" and self.grid_convergence_applied is not None:
            return self.grid_convergence_applied
        return self.grid_convergence

    def model_date(self, ways: str) -> dt.date | None:
        """The survey date at which a geomagnetic model gives every station's field and
        declination. Raises ``ValueError`` for a survey of trajectories begun on several
        days (``survey_date_last``), naming ``ways``: how to give what the model would."""
        if self.survey_date_last is not None:
            raise ValueError(
                f"the survey's trajectories began on several days ({self.survey_dates()}): "
                f"one date's geomagnetic field and declination are not every station's; "
                f"{ways}, or read one trajectory at a time (the witsml reader's option "
                "trajectory)"
            )
        return self.survey_date

    def survey_dates(self) -> str | None:
        """The survey date as a report states it: ``2026-03-02``, or of trajectories begun
        on several days the range, ``2025-02-10 to 2026-03-02``."""
        first = self.survey_date.isoformat() if self.survey_date else None
        if self.survey_date_last is None:
            return first
        return f"{first or '?'} to {self.survey_date_last.isoformat()}"

    def merged(self, other: WellMetadata | dict[str, Any]) -> WellMetadata:
        """A copy where every field set in ``other`` overrides this one; a ``survey_date``
        set without a ``survey_date_last`` is the one date (this one's last day cleared).
        Raises :class:`~pipeline.errors.ParameterError`: the dates out of order."""
        update = (
            other.model_dump(exclude_unset=True)
            if isinstance(other, WellMetadata)
            else WellMetadata.model_validate(other).model_dump(exclude_unset=True)
        )
        if "survey_date" in update:
            update.setdefault("survey_date_last", None)
        try:
            return self.model_copy(update=update)._dates_in_order()
        except ValueError as exc:
            raise ParameterError(f"well metadata: {exc}") from None


_ANGLE, _LENGTH = 1e-6, 1e-3  # deg; m
AGREEING: dict[str, float] = {
    "latitude": _ANGLE,
    "longitude": _ANGLE,
    "easting": _LENGTH,
    "northing": _LENGTH,
    "elevation": _LENGTH,
    "declination": _ANGLE,
    "grid_convergence": _ANGLE,
    "magnetic_field": 0.01,  # nT
    "magnetic_dip": _ANGLE,
    "declination_applied": _ANGLE,
    "grid_convergence_applied": _ANGLE,
}
"""Number fields → the spread (in the field's unit: deg, m, nT) within which several
headers state one value (:func:`agreed`: a latitude 61.25 beside 61.2500001 is the same
wellhead); text and dates agree only when equal."""


def _agree(name: str, values: list[Any]) -> bool:
    """Whether the values of field ``name`` stated by several headers are one value."""
    if name in AGREEING:
        return bool(max(values) - min(values) <= AGREEING[name])
    return len(set(values)) == 1


def agreed(headers: Mapping[str, WellMetadata]) -> tuple[WellMetadata, dict[str, dict[str, Any]]]:
    """What the headers of several input files (by input name) say of the run as one: the
    fields where they differ (numbers by more than :data:`AGREEING` allows) — each input's
    value, and the update stating the run's well
    (over the headers merged): survey dates, where they differ or one header states a range,
    as their range (``survey_date`` the first, ``survey_date_last`` the last: a header of
    the first day alone merged last ends no range), any other field left unstated (no one
    file's value is the run's: each table keeps its own,
    :meth:`~pipeline.registry.StageContext.well_for`).
    Values as JSON (dates ISO)."""
    dumped = {k: h.model_dump(mode="json", exclude_none=True) for k, h in headers.items()}
    differ: dict[str, dict[str, Any]] = {}
    for name in WellMetadata.model_fields:
        stated = {k: d[name] for k, d in dumped.items() if name in d}
        if stated and not _agree(name, list(stated.values())):
            differ[name] = stated
    update: dict[str, Any] = {name: None for name in differ}
    if "survey_date" in differ or any(h.survey_date_last for h in headers.values()):
        days = [d for h in headers.values() for d in (h.survey_date, h.survey_date_last) if d]
        update["survey_date"], update["survey_date_last"] = min(days), max(days)
    return WellMetadata().model_copy(update=update), differ


APPLIED_REFUSED: dict[str, tuple[NorthReference, ...]] = {
    "grid_convergence_applied": ("true", "magnetic"),
    "declination_applied": ("magnetic",),
}
"""A correction applied to azimuths → the north references whose azimuths carry none: true-
and magnetic-north azimuths no grid correction, magnetic ones no declination."""


def contradicts_north(north: NorthReference | None, name: str, value: float) -> bool:
    """Whether a correction ``name`` of ``value`` deg said to be applied to azimuths referred
    to ``north`` north contradicts it (:data:`APPLIED_REFUSED`; 0 is none applied)."""
    return value != 0.0 and north in APPLIED_REFUSED.get(name, ())


def attach(table: pa.Table, well: WellMetadata) -> pa.Table:
    """The table with ``well`` stored in its schema metadata."""
    return table.replace_schema_metadata(attached(table.schema, well))


def attached(schema: pa.Schema, well: WellMetadata) -> dict[bytes, bytes]:
    """The schema metadata of ``schema`` with ``well`` stored in it."""
    meta = dict(schema.metadata or {})
    meta[WELL_KEY] = well.model_dump_json(exclude_unset=True).encode()
    return meta


def well_of(table: pa.Table | pa.Schema) -> WellMetadata | None:
    """The well metadata stored in a table's schema (or a schema), if any."""
    schema = table if isinstance(table, pa.Schema) else table.schema
    raw = (schema.metadata or {}).get(WELL_KEY)
    if raw is None:
        return None
    return WellMetadata.model_validate(jsontext.loads(raw))


class WellMismatchError(GyropipeError, ValueError):
    """Tables to be combined (runs of a definitive survey, an in-run and its out-run) name
    different wells in their headers: names each table's port and the well it names."""


IDENTITY_FIELDS = {"well": "well", "uwi": "UWI"}
"""Well metadata fields naming the well (→ their label in messages); the wellbore is not
one (a sidetrack's survey lists its parent's stations above the kick-off)."""
API_WELL_DIGITS = 10
"""Digits of an API number naming the well: state, county, well (those after them name the
wellbore and the event: a sidetrack's 12-digit API is its well's)."""


def _identity(name: str, value: str) -> str:
    """``value`` of identity field ``name`` as compared: letters and digits, case folded (J-12,
    j 12 and J12 are one name); an API number (digits only) by its first ten digits."""
    key = "".join(c for c in value.casefold() if c.isalnum())
    if name == "uwi" and key.isdigit() and len(key) > API_WELL_DIGITS:
        return key[:API_WELL_DIGITS]
    return key


def one_well(tables: Mapping[str, pa.Table | pa.Schema]) -> None:
    """Check that ``tables`` (by port) are of one well: where two of their headers
    (:func:`well_of`) both state a well name, or both a UWI/API, these agree (compared as
    :func:`_identity` says). A table stating neither passes: its well is unknown, not another.
    Raises :class:`WellMismatchError` naming each port and the well its header names."""
    headers = {port: well_of(table) or WellMetadata() for port, table in tables.items()}
    for name in IDENTITY_FIELDS:
        stated = {p: getattr(h, name) for p, h in headers.items() if getattr(h, name)}
        if len({_identity(name, v) for v in stated.values()}) > 1:
            break
    else:
        return
    named = []
    for port, header in headers.items():
        parts = [
            f"{label} {getattr(header, name)!r}"
            for name, label in IDENTITY_FIELDS.items()
            if getattr(header, name)
        ]
        named.append(f"{port}: {', '.join(parts) or 'no well named'}")
    raise WellMismatchError(
        f"the runs are of different wells ({'; '.join(named)}): runs of one well only can "
        "be combined; give the runs of one well, or correct the header that names the wrong one"
    )
