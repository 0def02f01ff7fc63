"""Options of the CSV reader, and vendor profiles: YAML files of the same options.

A profile (``profile: path/to/vendor.yaml``, relative to the current directory) holds any
option but ``profile`` and ``default_north_reference``, plus a free-text ``description``.
It is merged *under* the explicit options: an option given explicitly wins, mappings
(``columns``, ``aliases``, ``units``, ``conventions``) are merged key by key, and an explicit
``md_unit``/``angle_unit`` also replaces the profile's ``units`` of those columns. A
profile's unit is for a header cell without one: a header stating another unit is refused
(the profile was written for files without it; an explicit option may still override it).

An invalid profile (unknown key, bad value, duplicate key, malformed YAML) raises
:class:`~pipeline.errors.InputFileError` naming the profile file and the line of the first
problem; its message lists every problem as ``file:line:column: message`` (the
:class:`~pipeline.errors.SpecError` built by :mod:`pipeline.yamlsource` is its cause).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from pipeline.errors import InputFileError, SpecError, UnitError
from pipeline.inputfiles import InputPath
from pipeline.io.conventions import Conventions
from pipeline.io.mnemonics import CURVES
from pipeline.plausibility import AngleUnitConfirmed, NullStations, SurveyStations
from pipeline.units import conversion_factor
from pipeline.well import DefaultNorthReference, NorthReference
from pipeline.yamlsource import load_mapping, validate_located

SHORTHANDS = {"md_unit": ("md",), "angle_unit": ("inc", "azi")}
"""Unit options that stand for ``units`` of these columns."""


def _known(name: str) -> str:
    if name not in CURVES:
        raise ValueError(f"unknown column {name!r} (known: {', '.join(CURVES)})")
    return name


CanonicalName = Annotated[str, AfterValidator(_known)]


def _checked_unit(unit: str, quantity: str) -> str:
    """``unit`` if it measures ``quantity``; else ValueError (for pydantic) with the reason."""
    try:
        conversion_factor(unit, quantity)
    except UnitError as exc:
        raise ValueError(str(exc)) from None
    return unit


class CsvSettings(BaseModel):
    """What a reader option and a profile may both set; every one may be left to detection."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    delimiter: Literal[",", ";", "\t", "|"] | None = Field(
        None, description="field delimiter (default: detected from the header row)"
    )
    decimal: Literal[".", ","] | None = Field(
        None, description="decimal mark (default: ',' only when no value uses '.')"
    )
    header_line: int | None = Field(
        None, ge=1, description="1-based line of the header row (default: searched for)"
    )
    columns: dict[CanonicalName, str] = Field(
        default_factory=dict,
        description="header text of a column, by canonical name (wins over any guess)",
    )
    aliases: dict[str, CanonicalName] = Field(
        default_factory=dict,
        description="canonical column named by a header text (compared like mnemonics, "
        "before the built-in mnemonics table)",
    )
    units: dict[CanonicalName, str] = Field(
        default_factory=dict,
        description="unit of a column, by canonical name; overrides the header's",
    )
    md_unit: str | None = Field(None, description="unit of md (short for units: {md: …})")
    angle_unit: str | None = Field(
        None, description="unit of inc and azi (short for units: {inc: …, azi: …})"
    )
    angle_unit_confirmed: AngleUnitConfirmed = False
    null_stations: NullStations = "error"
    stations: SurveyStations = "survey"
    north_reference: NorthReference | None = Field(
        None, description="north reference of the azimuths (true, grid or magnetic)"
    )
    conventions: Conventions = Field(
        default_factory=Conventions,
        description="vendor axis and sign conventions of the sensor columns (samples)",
    )

    @field_validator("units")
    @classmethod
    def _units(cls, units: dict[str, str]) -> dict[str, str]:
        for name, unit in units.items():
            quantity = CURVES[name].quantity
            if quantity is None:
                raise ValueError(f"{name}: column {name!r} has no unit")
            try:
                _checked_unit(unit, quantity)
            except ValueError as exc:
                raise ValueError(f"{name}: {exc}") from None
        return units

    @field_validator("md_unit")
    @classmethod
    def _length(cls, unit: str | None) -> str | None:
        return None if unit is None else _checked_unit(unit, "length")

    @field_validator("angle_unit")
    @classmethod
    def _angle(cls, unit: str | None) -> str | None:
        return None if unit is None else _checked_unit(unit, "angle")

    @model_validator(mode="after")
    def _decimal_not_delimiter(self) -> CsvSettings:
        if self.decimal == "," and self.delimiter == ",":
            raise ValueError("decimal ',' needs a delimiter other than ','")
        return self

    def unit_of(self, name: str) -> str | None:
        """The declared unit of column ``name``: ``units``, else a shorthand, else None."""
        if name in self.units:
            return self.units[name]
        return next(
            (getattr(self, opt) for opt, names in SHORTHANDS.items() if name in names), None
        )


class CsvProfile(CsvSettings):
    """A vendor profile: reader options kept in a YAML file."""

    description: str | None = Field(None, description="what files this profile reads")


class CsvOptions(CsvSettings):
    """Options of the CSV reader (both kinds: stations and samples)."""

    profile: InputPath | None = Field(
        None,
        description="YAML profile of options merged under these (relative to the current "
        "directory)",
    )
    default_north_reference: DefaultNorthReference = None

    def resolved(self) -> CsvOptions:
        """These options with the profile, if any, merged under them."""
        if self.profile is None:
            return self
        profile = load_profile(self.profile)
        top = self.model_dump(exclude_unset=True, exclude={"profile"})
        base = profile.model_dump(exclude_unset=True, exclude={"description"})
        shadowed = {n for opt, names in SHORTHANDS.items() if opt in top for n in names}
        base["units"] = {n: u for n, u in base.get("units", {}).items() if n not in shadowed}
        try:
            return CsvOptions.model_validate(_merge(base, top))
        except ValidationError as exc:
            reasons = "; ".join(e["msg"] for e in exc.errors())
            raise InputFileError(
                self.profile, f"the reader options conflict with this profile: {reasons}"
            ) from None


def profile_units(options: CsvOptions) -> frozenset[str]:
    """The columns whose unit comes from the profile (the explicit options give none): a
    profile fills in the units its vendor's headers lack, it never overrides one a header
    states (:func:`pipeline.io.csv.header.factor` refuses that)."""
    if options.profile is None:
        return frozenset()
    profile = load_profile(options.profile)
    return frozenset(n for n in CURVES if profile.unit_of(n) and options.unit_of(n) is None)


def load_profile(path: Path) -> CsvProfile:
    """Read and validate a profile; any problem is an InputFileError located in it."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputFileError(path, f"cannot read the profile: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise InputFileError(path, f"the profile is not UTF-8 text: {exc.reason}") from None
    try:
        raw, source, problems = load_mapping(
            text, str(path), "a CSV profile must be a mapping of reader options"
        )
        profile = validate_located(CsvProfile, raw, source, problems)
        if problems:  # duplicate keys, refused tags: fatal in a profile too
            raise SpecError(problems)
    except SpecError as exc:
        found = sorted(exc.problems, key=lambda p: (p.location.line, p.location.column))
        raise InputFileError(
            path,
            f"invalid CSV profile ({len(found)} problem{'s' * (len(found) > 1)}): "
            + "; ".join(str(p) for p in found),
            line=found[0].location.line,
        ) from exc
    return profile


def _merge(base: dict[str, Any], top: dict[str, Any]) -> dict[str, Any]:
    """``base`` updated by ``top``, nested mappings merged key by key."""
    out = dict(base)
    for key, value in top.items():
        below = out.get(key)
        out[key] = (
            _merge(below, value) if isinstance(below, dict) and isinstance(value, dict) else value
        )
    return out
