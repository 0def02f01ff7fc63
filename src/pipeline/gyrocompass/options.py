"""Parameters of gyrocompassing (angles deg, rates °/h; other units as each field says)."""

from __future__ import annotations

from typing import Literal, Self

from pydantic import BaseModel, ConfigDict, Field

from pipeline.gyrocompass.azimuth import Method
from pipeline.gyrocompass.systematic import ToolErrors

ACC_BIAS = (
    "accelerometer bias, m/s² (1σ per axis). Default: the tool's (the stage takes it from the "
    "tool catalogue's entry that the well's tool_preset names, else from ISCWSA GYRO-NS's "
    "AXYZ-ZB)"
)
ACC_MISALIGNMENT = (
    "accelerometer axis misalignment, mrad (1σ per off-diagonal term); default as acc_bias "
    "(GYRO-NS AXYZ-MIS)"
)
ACC_SCALE_FACTOR = (
    "accelerometer scale-factor error, ppm (1σ per axis); default as acc_bias (GYRO-NS AXYZ-SF)"
)


class AccelerometerOptions(BaseModel):
    """The 1σ accelerometer error magnitudes of the tool, for the σ they add to what is
    measured against the accelerometers (the compass's inclination and toolface, the
    magnetometer diagnosis's dip); unset: the stage takes the tool's."""

    acc_bias: float | None = Field(None, ge=0, description=ACC_BIAS)
    acc_misalignment: float | None = Field(None, ge=0, description=ACC_MISALIGNMENT)
    acc_scale_factor: float | None = Field(None, ge=0, description=ACC_SCALE_FACTOR)

    def tool_errors(self) -> ToolErrors:
        """The magnitudes these options hold (and their ``g_sensitivity`` where they have
        one); an unset one counts as 0 (the stage sets every one from the tool first)."""
        return ToolErrors(
            g_sensitivity=getattr(self, "g_sensitivity", None) or 0.0,
            acc_bias=self.acc_bias or 0.0,
            acc_misalignment=self.acc_misalignment or 0.0,
            acc_scale_factor=self.acc_scale_factor or 0.0,
        )

    def with_defaults(self, tool: ToolErrors) -> Self:
        """A copy whose unset tool error magnitudes are ``tool``'s."""
        fields = type(self).model_fields
        unset = {
            name: getattr(tool, name)
            for name in ToolErrors.__dataclass_fields__
            if name in fields and getattr(self, name) is None
        }
        return self.model_copy(update=unset)


class CompassOptions(AccelerometerOptions):
    """Compassing parameters (angles deg, rates °/h); the accelerometer errors enter σ_inc
    and the σ of the gravity toolface."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    gyro_axes: Literal["auto", "x", "xy", "xyz"] = Field(
        "auto", description="gyro axes to use (auto: every gyro column present)"
    )
    azimuth_method: Method = Field("ml", description="ml, auto (sine/atan2), sine or atan2")
    vertical_below: float = Field(
        3.0, gt=0, lt=45, description="inclination below which the near-vertical mode is used"
    )
    trend: bool = Field(True, description="fit a linear gyro trend (needs enough positions)")
    gyro_sigma: float | None = Field(
        None,
        gt=0,
        description="σ of one position's mean gyro reading when the readings "
        "carry no std/n columns",
    )
    acc_sigma: float | None = Field(
        None, gt=0, description="σ of one position's mean acceleration, m/s², likewise"
    )
    noise_floor: float = Field(
        0.0, ge=0, description="added in quadrature to each position's gyro σ (bias instability)"
    )
    consistency: float = Field(
        1e-3, gt=0, lt=1, description="χ² tail probability below which a station is flagged"
    )
    frame_tolerance: float = Field(
        2.0, gt=0, description="largest disagreement of frame angle and accelerometer toolface"
    )
    max_sigma_azi: float = Field(
        5.0,
        gt=0,
        description="σ_azi, deg, above which a station is flagged poor_azimuth (σ includes "
        "the tool errors compassing cannot remove, e.g. a gyro's g-sensitivity)",
    )
    ambiguity: float = Field(
        1e-3,
        gt=0,
        lt=1,
        description="probability (equal priors) of the mirror azimuth 180° − A above which a "
        "station is rejected: toward horizontal a transverse gyro's high-side component "
        "carries little cos A, so A and 180° − A fit its readings almost alike",
    )
    z_bias_sigma: float | None = Field(
        None,
        gt=0,
        description="σ of the axial gyro's bias, °/h: when given, a three-axis "
        "tool's z gyro joins the azimuth fit (its bias is not removed by turning the frame)",
    )
    earth_rate_tolerance: float = Field(
        0.2,
        gt=0,
        lt=1,
        description="largest relative departure of the fitted horizontal Earth rate from "
        "Ω cos φ (and, when the z gyro joins the fit, of the vertical one from Ω sin φ), "
        "beyond 4 σ of the fit, before a station is rejected (rates in the wrong unit, a "
        "dead or mis-scaled gyro, a wrong latitude)",
    )
    acc_resolution: float = Field(
        1.0,
        gt=0,
        description="accelerometer resolution, µg (1 µg = 9.80665e-6 m/s²), added in "
        "quadrature to each position's accelerometer σ: a tilt below it cannot be seen, so "
        "noise-free data at 0° inclination give an undefined azimuth, not a tiny σ",
    )
    tilt_detection: float = Field(
        3.0,
        gt=0,
        description="multiple of its σ by which the measured horizontal gravity must exceed "
        "zero for the tilt to define an azimuth; below it the azimuth is NaN and flagged "
        "azimuth_undefined",
    )
    g_sensitivity: float | None = Field(
        None,
        ge=0,
        description="g-dependent bias of a transverse gyro, (°/h)/g of transverse specific "
        "force (1σ): turning the frame cannot remove it, so it enters σ_azi as "
        "≈ sin I · g_sensitivity / (Ω cos φ). Default: the tool's (the stage takes it from "
        "the tool catalogue's entry that the well's tool_preset names, else from ISCWSA "
        "GYRO-NS's GXY-G1)",
    )
