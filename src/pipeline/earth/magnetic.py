"""The geomagnetic reference a stage applies, and where each value came from: the stage's
own ``magnetic`` parameter, the well metadata (``magnetic_field``, ``magnetic_dip``,
``declination``: a ``well:`` block, ``--well``, the file header), or the geomagnetic model at
the well's site and survey date. Nothing is assumed: without any of them the stage refuses.
Field in nT, angles in degrees."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from pipeline.earth.geomagnetic import ModelKey, field_model, reference_field
from pipeline.earth.site import MagneticReference
from pipeline.errors import GyropipeError, MissingSiteError
from pipeline.well import WellMetadata

GIVEN_IN_WELL = "given in the well metadata"


class AppliedMagnetic(BaseModel):
    """A geomagnetic reference as applied: the values and the source of each."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    reference: MagneticReference
    field_source: str = Field(description="where the total field and dip came from")
    declination_source: str = Field(description="where the declination came from")

    def words(self) -> str:
        """ "total field 50,000 nT, dip 70.00°, declination 0.00° (given in the well
        metadata)", one source named once when both agree."""
        ref = self.reference
        field = f"total field {ref.total_field:,.0f} nT, dip {ref.dip:.2f}°"
        declination = f"declination {ref.declination:.2f}°"
        if self.field_source == self.declination_source:
            return f"{field}, {declination} ({self.field_source})"
        return f"{field} ({self.field_source}), {declination} ({self.declination_source})"


def applied_magnetic(
    given: MagneticReference | None,
    well: WellMetadata,
    *,
    stage: str,
    param: str = "magnetic",
    model: ModelKey = "wmm2025",
) -> AppliedMagnetic:
    """The reference ``stage`` applies: its parameter ``param`` when ``given``; else the
    well's ``magnetic_field`` and ``magnetic_dip`` when both are set, else ``model`` at the
    well's latitude, longitude, elevation and survey date; the well's ``declination`` when
    set, else the model's. Raises :class:`~pipeline.errors.MissingSiteError` naming the
    stage and every way to give what is missing, a ``ValueError`` where the model would be
    evaluated for trajectories begun on several days
    (:meth:`~pipeline.well.WellMetadata.model_date`)."""
    if given is not None:
        source = f"given in the pipeline ({stage}.{param})"
        return AppliedMagnetic(reference=given, field_source=source, declination_source=source)
    field = (
        None
        if well.magnetic_field is None or well.magnetic_dip is None
        else (well.magnetic_field, well.magnetic_dip)
    )
    declination = well.declination
    field_source = declination_source = GIVEN_IN_WELL
    if field is None or declination is None:
        date = well.model_date(
            f"give the well's `magnetic_field`, `magnetic_dip` and `declination`, or the "
            f"{stage} stage's `{param}`"
        )
        missing = [
            name
            for name, value in (
                ("latitude", well.latitude),
                ("longitude", well.longitude),
                ("survey_date", date),
            )
            if value is None
        ]
        if missing or well.latitude is None or well.longitude is None or not date:
            raise MissingMagneticError(stage, missing, param)
        site = reference_field(
            well.latitude, well.longitude, well.elevation or 0.0, date, model=model
        ).reference()
        where = (
            f"{field_model(model).name} at {_signed(well.latitude, 'NS')} "
            f"{_signed(well.longitude, 'EW')}, {date.isoformat()}"
        )
        if field is None:
            field, field_source = (site.total_field, site.dip), where
        if declination is None:
            declination, declination_source = site.declination, where
    reference = MagneticReference(total_field=field[0], dip=field[1], declination=declination)
    return AppliedMagnetic(
        reference=reference, field_source=field_source, declination_source=declination_source
    )


def _signed(degrees: float, hemispheres: str) -> str:
    """``61.2500° N``, ``0.5000° W``."""
    return f"{abs(degrees):.4f}° {hemispheres[0] if degrees >= 0 else hemispheres[1]}"


class MissingMagneticError(MissingSiteError):
    """A stage needs the geomagnetic reference and nothing gives it (see
    :func:`applied_magnetic`)."""

    def __init__(self, stage: str, missing: list[str], param: str) -> None:
        self.stage, self.missing, self.param = stage, missing, param
        fields = ", ".join(f"`{name}`" for name in missing)
        GyropipeError.__init__(
            self,
            f"the {stage} stage needs the geomagnetic reference: give the well's "
            "`magnetic_field` (nT), `magnetic_dip` and `declination` (deg), or its site for "
            f"the geomagnetic model (missing: {fields}) — in the pipeline's `well:` block, on "
            f"the command line (--well magnetic_field=…) or in the input file's header — or "
            f"the {stage} stage's `{param}`",
        )

    def in_python(self) -> MissingSiteError:
        """As it is: its fields are named as the well's (``well={…}`` in Python)."""
        return self
