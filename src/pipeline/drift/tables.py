"""Contracts of the drift tables: calibration readings and results (seed 000), drift-corrected
free-gyro surveys with their in-run/out-run QC, Allan deviations, noise parameters and the
recommended compassing dwell.

Angles in degrees, times in seconds, drift rates in °/min and °/h, gyro rates in °/h,
accelerations in m/s².
"""

from __future__ import annotations

from typing import Any, ClassVar

import pyarrow as pa

from pipeline.contracts import TableContract, column
from pipeline.tables import ACCEL_UNIT, RATE_UNIT, FreeGyroReadings, Stations


class CalibrationReadings(TableContract):
    """Azimuth readings of a free-gyro inclinometer on a calibration stand: several series,
    one after another, each a sweep of set azimuths (0°, 30°, … as in seed 000).

    Give the error either as ``azimuth_error`` or as ``measured_azimuth`` (error = measured −
    set, wrapped to ±180°), and the time either per reading (``time``) or per series
    (``series_start``/``series_end``: readings then spread evenly over the series, in row
    order). Rows without ``instrument`` belong to the well's ``tool_serial``."""

    group_by = "instrument"

    instrument: str | None = column(unit=None, description="instrument serial number", default=None)
    series: int = column(unit=None, description="series number (any integers, one per sweep)")
    set_azimuth: float = column(
        unit="deg", ge=0, le=360, description="azimuth set on the calibration stand"
    )
    measured_azimuth: float | None = column(
        unit="deg", description="azimuth read by the instrument", default=None
    )
    azimuth_error: float | None = column(
        unit="deg", description="measured minus set azimuth", default=None
    )
    time: float | None = column(unit="s", description="time of the reading", default=None)
    series_start: float | None = column(
        unit="s", description="start time of the reading's series", default=None
    )
    series_end: float | None = column(
        unit="s", description="end time of the reading's series", default=None
    )
    temperature: float | None = column(
        unit="degC", description="instrument temperature at the reading", default=None
    )


class CalibrationResult(TableContract):
    """Drift-rate estimates of each calibrated instrument, one row per estimate; the
    instrument's linearity test is repeated on each of its rows. ``selected`` marks the
    estimate that drift correction uses by default. A batch's ledger records, per well, the
    calibration results a run used."""

    in_ledger: ClassVar[bool] = True

    instrument: str = column(unit=None, description="instrument serial number")
    method: str = column(
        unit=None,
        description="adjacent (two neighbouring series), pair (two other series), mean (of "
        "the adjacent ones), grouped (first half vs second half of the series), fit "
        "(weighted straight line through all series means) or traditional (two readings)",
    )
    label: str = column(unit=None, description="which series or readings the estimate uses")
    drift_deg_min: float = column(unit="deg/min", description="drift rate")
    drift_deg_h: float = column(unit="deg/h", description="drift rate")
    sigma_deg_min: float = column(unit="deg/min", ge=0, description="σ of the drift rate")
    sigma_deg_h: float = column(unit="deg/h", ge=0, description="σ of the drift rate")
    interval: float = column(unit="s", gt=0, description="time between the compared means")
    gain: float = column(
        unit=None,
        ge=0,
        finite=False,
        description="σ of the traditional two-reading estimate over `control_interval` "
        "divided by this estimate's σ",
    )
    gain_claimed: float = column(
        unit=None, ge=0, description="seed 000's claimed gain √(n(n−1)/2), n readings/series"
    )
    reading_sigma: float = column(
        unit="deg", ge=0, description="σ of one reading after removing pattern and drift"
    )
    selected: bool = column(unit=None, description="the estimate used for correction")
    chi2: float = column(
        unit=None, ge=0, finite=False, description="χ² of the series means about a straight line"
    )
    dof: int = column(unit=None, ge=0, description="degrees of freedom of the χ² (series − 2)")
    p_value: float = column(
        unit=None,
        ge=0,
        le=1,
        finite=False,
        description="p-value of the linearity test (NaN: fewer than 3 series)",
    )
    verdict: str = column(unit=None, description="linear, non-linear: … or untested: …")
    calibration_date: str | None = column(
        unit=None,
        description="day the calibration was recorded, ISO 8601 (2026-05-12); null: not stated",
        default=None,
    )
    time_span: float | None = column(
        unit="s",
        ge=0,
        description="time from the instrument's first calibration reading to its last: the "
        "span its drift was seen over",
        default=None,
    )
    temperature_min: float | None = column(
        unit="degC",
        description="lowest temperature of its calibration readings (null: none stated)",
        default=None,
    )
    temperature_max: float | None = column(
        unit="degC",
        description="highest temperature of its calibration readings (null: none stated)",
        default=None,
    )

    @classmethod
    def ledger_entry(cls, table: pa.Table) -> dict[str, Any]:
        """The instruments the result calibrates and its selected estimates (instrument,
        method, drift rate °/h)."""
        rows = table.select(["instrument", "method", "drift_deg_h", "selected"]).to_pylist()
        return {
            "instruments": sorted({r["instrument"] for r in rows}),
            "selected": [
                {k: r[k] for k in ("instrument", "method", "drift_deg_h")}
                for r in rows
                if r["selected"]
            ],
        }


class CalibrationSeries(TableContract):
    """Per series: the mean azimuth error (pattern removed) at the series' mid-time."""

    instrument: str = column(unit=None, description="instrument serial number")
    series: int = column(unit=None, description="series number")
    readings: int = column(unit=None, ge=1, description="readings in the series")
    mid_time: float = column(unit="s", description="mean time of the series' readings")
    mean_error: float = column(unit="deg", description="mean azimuth error of the series")
    sigma_mean: float = column(unit="deg", ge=0, description="σ of mean_error")
    residual_std: float = column(
        unit="deg", ge=0, description="scatter of one reading after pattern and drift removal"
    )


class CorrectedFreeGyroReadings(FreeGyroReadings):
    """Free-gyro readings with the drift removed: ``azi = azi_raw − correction``."""

    azi_raw: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth as read"
    )
    correction: float = column(unit="deg", description="drift correction subtracted")
    sigma_azi: float = column(unit="deg", ge=0, description="predicted σ of the corrected azimuth")
    drift_rate: float | None = column(
        unit="deg/h",
        description="drift rate the survey was corrected with (the same on every row)",
        default=None,
    )
    sigma_drift_rate: float | None = column(
        unit="deg/h",
        ge=0,
        description="σ of drift_rate: the calibration's or the given one; of a tie-in "
        "misclosure √2·σ_r / (t_last − t_first)",
        default=None,
    )


class DriftStations(Stations):
    """Drift-corrected stations (in-run and out-run readings of a station combined)."""

    station: int = column(unit=None, ge=0, description="station index")
    sigma_azi: float = column(unit="deg", ge=0, description="predicted σ of the azimuth")
    readings: int = column(unit=None, ge=1, description="readings combined")


class InOutQc(TableContract):
    """In-run vs out-run comparison of drift-corrected readings at each station read twice;
    a row passes when both differences are within their tolerances."""

    station: int = column(unit=None, ge=0, description="station index")
    md: float = column(unit="m", description="measured depth")
    inc_in: float = column(unit="deg", description="in-run inclination")
    inc_out: float = column(unit="deg", description="out-run inclination")
    inc_diff: float = column(unit="deg", description="in − out inclination")
    azi_in: float = column(unit="deg", description="in-run corrected azimuth")
    azi_out: float = column(unit="deg", description="out-run corrected azimuth")
    azi_diff: float = column(unit="deg", description="in − out azimuth, wrapped to ±180°")
    sigma_azi_diff: float = column(unit="deg", ge=0, description="predicted σ of azi_diff")
    inc_tolerance: float = column(unit="deg", ge=0, description="allowed |inc_diff|")
    azi_tolerance: float = column(unit="deg", ge=0, description="allowed |azi_diff|")
    tie_in: bool = column(
        unit=None,
        description="the tie-in station: judged against the azimuth tolerance at any "
        "inclination (its error shifts every azimuth); with the rate from its own misclosure, "
        "azi_out is its out-run reading corrected by the rate the other stations show",
    )
    passed: bool = column(unit=None, description="both differences within tolerance")


class AllanResult(TableContract):
    """Overlapping Allan deviation per sensor axis at octave averaging times (axes the
    record lacks are null)."""

    tau: float = column(unit="s", gt=0, monotonic="strict", description="averaging time")
    clusters: int = column(unit=None, ge=1, description="overlapping differences averaged")
    gyro_x: float | None = column(unit=RATE_UNIT, description="gyro x Allan deviation")
    gyro_y: float | None = column(unit=RATE_UNIT, description="gyro y", default=None)
    gyro_z: float | None = column(unit=RATE_UNIT, description="gyro z", default=None)
    acc_x: float | None = column(unit=ACCEL_UNIT, description="accelerometer x", default=None)
    acc_y: float | None = column(unit=ACCEL_UNIT, description="accelerometer y", default=None)
    acc_z: float | None = column(unit=ACCEL_UNIT, description="accelerometer z", default=None)


class NoiseParameters(TableContract):
    """IEEE Std 952 noise terms of each axis, in the units named beside them: gyro ARW
    deg/sqrt(h), bias instability deg/h, RRW deg/h/sqrt(h); accelerometer VRW
    m/s/sqrt(h), bias instability m/s2, acceleration random walk m/s2/sqrt(h)."""

    axis: str = column(unit=None, description="gyro_x, …, acc_z")
    arw: float = column(unit=None, ge=0, description="angle (velocity) random walk")
    arw_unit: str = column(unit=None, description="unit of arw")
    bias_instability: float = column(unit=None, ge=0, description="bias instability")
    bias_instability_unit: str = column(unit=None, description="unit of bias_instability")
    rrw: float = column(unit=None, ge=0, description="rate (acceleration) random walk")
    rrw_unit: str = column(unit=None, description="unit of rrw")
    bias_model: str = column(unit=None, description="flicker (flat floor) or gauss_markov")
    correlation_time: float | None = column(
        unit="s", gt=0, description="Gauss–Markov correlation time (null: flicker model)"
    )
    adev_min: float = column(
        unit=None, ge=0, description="smallest measured Allan deviation (bias_instability_unit)"
    )
    tau_min: float = column(unit="s", gt=0, description="averaging time of adev_min")
    fit_rms: float = column(
        unit=None, ge=0, description="RMS relative misfit of the fitted curve to the deviations"
    )


class DwellRecommendation(TableContract):
    """Shortest dwell per frame position reaching the target azimuth σ at the worst azimuth
    and starting toolface, for the given inclination and latitude."""

    axis: str = column(unit=None, description="gyro axis whose Allan deviation is used")
    latitude: float = column(unit="deg", ge=-90, le=90, description="site latitude")
    inclination: float = column(unit="deg", ge=0, le=180, description="design inclination")
    positions: int = column(unit=None, ge=4, description="frame positions per station")
    target_sigma_azi: float = column(unit="deg", gt=0, description="wanted azimuth σ")
    dwell: float = column(unit="s", gt=0, description="recommended time per position")
    station_time: float = column(unit="s", gt=0, description="positions × dwell + moves")
    sigma_rate: float = column(unit=RATE_UNIT, ge=0, description="per-position gyro σ")
    sigma_azi: float = column(unit="deg", ge=0, description="predicted azimuth σ at dwell")
    achievable: bool = column(unit=None, description="the target is met within max_dwell")
    best_dwell: float = column(unit="s", gt=0, description="dwell of the smallest azimuth σ")
    best_sigma_azi: float = column(unit="deg", ge=0, description="smallest azimuth σ")
