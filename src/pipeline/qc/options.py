"""Options of the validity checks: which checks there are, how strict each is, what a
failure does, and the errors the checks raise.

Tolerance of a reading (:class:`Tolerance`):
``√((sigma·σ)² + absolute² + (relative·|reference|)²)``, σ the standard deviation of the
measured value propagated (first order) from the σ of each mean reading, std/√n.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.earth.frames import FloatArray
from pipeline.earth.geomagnetic import ModelKey
from pipeline.errors import GyropipeError
from pipeline.gyrocompass.options import AccelerometerOptions

Policy = Literal["flag", "drop", "stop"]

GYRO_FLOOR = 0.5
"""°/h: three times the ISCWSA GYRO-NS 1σ gyro bias (0.15 °/h), rounded up."""


class QcInputError(GyropipeError, ValueError):
    """Inputs the checks cannot use: missing site metadata, readings without what a check
    needs."""


class QcStop(GyropipeError):
    """A check whose policy is ``stop`` failed. Names the station (or window) and the check;
    carries the QC results and, for stations, the summary (for the report)."""

    def __init__(
        self, where: str, check: str, detail: str, qc: pa.Table, summary: pa.Table | None
    ) -> None:
        self.where = where
        self.check = check
        self.qc = qc
        self.summary = summary
        super().__init__(f"{where}: check {check!r} failed and its policy is stop: {detail}")


class _Options(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Tolerance(_Options):
    """Tolerance of a statistical check, in the check's unit:
    ``√((sigma·σ)² + absolute² + (relative·|reference|)²)``; and what a failure does."""

    sigma: float = Field(0.0, ge=0, description="multiples of the measured value's σ")
    absolute: float = Field(0.0, ge=0, description="absolute part, in the check's unit")
    relative: float = Field(0.0, ge=0, description="fraction of |reference|")
    policy: Policy = Field(
        "flag", description="flag; drop (exclude the station downstream); stop (raise)"
    )

    def of(self, sigma: FloatArray, reference: FloatArray) -> FloatArray:
        """Tolerance for measured values of standard deviation ``sigma``."""
        out: FloatArray = np.sqrt(
            (self.sigma * sigma) ** 2 + self.absolute**2 + (self.relative * reference) ** 2
        )
        return out


class Limit(_Options):
    """An upper limit on a non-negative quantity, and what exceeding it does."""

    limit: float = Field(gt=0, description="largest allowed value, in the check's unit")
    policy: Policy = Field("flag", description="flag, drop or stop")


class QcOptions(_Options, AccelerometerOptions):
    """Tolerances, limits and policies of every check, and the window settings of
    continuous data. Defaults: ``sigma`` 3 (0.27 % false alarms per reading from white
    noise alone) plus absolute floors for systematic sensor errors — gyro 0.5 °/h (≈ 3 ×
    ISCWSA GYRO-NS bias 0.15 °/h), accelerometer 0.012 m/s² (≈ 1.2 mg, 3 × a 0.004 m/s²
    bias) — and the industry magnetic tolerances (ISCWSA eBook §22.1). The accelerometer
    error magnitudes enter the σ of a magnetometer bias the diagnosis estimates (the dip is
    measured against the accelerometers)."""

    earth_rate: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="|ω| vs Ω, °/h"
    )
    gravity: Tolerance = Field(
        Tolerance(sigma=3, absolute=0.012), description="|g| vs normal gravity, m/s²"
    )
    latitude: Tolerance = Field(
        Tolerance(sigma=3, absolute=1.9),
        description="latitude from gyros and accelerometers vs the site's, deg (1.9° is the "
        "0.5 °/h gyro floor seen across the 15.04 °/h Earth rate)",
    )
    horizontal_rate: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="ω_h vs Ω cos φ, °/h"
    )
    rate_along_gravity: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="ω·g/|g| vs −Ω sin φ, °/h"
    )
    magnetic_field: Tolerance = Field(
        Tolerance(absolute=300.0), description="|B| vs the reference total field, nT"
    )
    magnetic_dip: Tolerance = Field(
        Tolerance(absolute=0.25), description="dip vs the reference dip, deg"
    )
    earth_rate_fit: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR),
        description="single-axis/XY tools: fitted horizontal Earth rate vs Ω cos φ, °/h",
    )
    rest_gyro: Limit = Field(
        Limit(limit=100.0, policy="drop"),
        description="at rest: largest per-axis sample std of the gyros, °/h (also the "
        "stationary-window threshold)",
    )
    rest_acc: Limit = Field(
        Limit(limit=0.02, policy="drop"),
        description="at rest: largest per-axis sample std of the accelerometers, m/s² (also "
        "the stationary-window threshold)",
    )
    recording_end: Limit = Field(
        Limit(limit=1.0),
        description="the frame position the recording ended in: averaging time short of the "
        "survey's usual (the median of its other positions; all of it when too short to "
        "average), s",
    )
    missing_positions: Tolerance = Field(
        Tolerance(),
        description="frame positions a station lacks of the survey's usual number (the most "
        "common number at its stations), count",
    )
    unread_stop: Tolerance = Field(
        Tolerance(policy="drop"),
        description="a stop the tool made (its depth held) with no dwell long or steady "
        "enough to read, numbered as a station without readings: stops unread, count",
    )
    rest_speed: float = Field(
        0.02, gt=0, description="windows: largest |dMD/dt| (LSQ slope) of a stationary one, m/s"
    )
    steady_accel: float = Field(
        0.02,
        gt=0,
        description="windows: the dip is checked only where the MD acceleration (quadratic "
        "fit) is below this, m/s² (an acceleration a tilts the measured gravity by a/g rad; "
        "without MD, only in stationary windows)",
    )
    motion_rate: Limit = Field(
        Limit(limit=100.0), description="moving windows: largest |ω| of any sample, deg/s"
    )
    motion_accel: Limit = Field(
        Limit(limit=5.0),
        description="moving windows: largest ||a| − g₀| of any sample, m/s² (a lower bound "
        "of the tool's own acceleration)",
    )
    gyro_saturation: Limit = Field(
        Limit(limit=297.0),
        description="moving windows: largest |gyro axis| of any sample, deg/s (99 % of a "
        "±300 deg/s full scale: set from the tool)",
    )
    acc_saturation: Limit = Field(
        Limit(limit=19.4),
        description="moving windows: largest |accelerometer axis| of any sample, m/s² (99 % "
        "of a ±2 g full scale: set from the tool)",
    )
    window: float = Field(10.0, gt=0, description="length of a continuous-data window, s")
    step: float = Field(5.0, gt=0, description="step between window starts, s")
    vertical_below: float = Field(
        3.0,
        gt=0,
        lt=45,
        description="earth_rate_fit: inclination below which the fit is "
        "referenced to the frame angle, deg",
    )
    fit_trend: bool = Field(True, description="earth_rate_fit: fit a linear gyro trend too")
    isolation_margin: float = Field(
        1.0,
        gt=0,
        description="fault isolation: how much better (sum of squared residuals in units of "
        "their tolerance) the best sensor must explain a station than the runner-up",
    )
    magnetic_model: ModelKey = Field(
        "wmm2025", description="geomagnetic model when the site gives no magnetic reference"
    )


DEFAULTS = QcOptions()

CHECKS = (
    "earth_rate",
    "gravity",
    "latitude",
    "horizontal_rate",
    "rate_along_gravity",
    "magnetic_field",
    "magnetic_dip",
    "earth_rate_fit",
    "rest_gyro",
    "rest_acc",
    "recording_end",
    "missing_positions",
    "unread_stop",
    "motion_rate",
    "motion_accel",
    "gyro_saturation",
    "acc_saturation",
)
"""Every check, in report order; each is the name of its option in :class:`QcOptions`."""
