"""Parameters of continuous-mode integration (the ``integrate_continuous`` stage's)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field


class ContinuousOptions(BaseModel):
    """Parameters of continuous-mode integration."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    spacing: float = Field(10.0, gt=0, description="MD spacing of the output stations, m")
    vertical_below: float = Field(
        3.0, gt=0, lt=90, description="inclination below which samples are flagged, deg"
    )
    odometer_window: float = Field(
        2.0,
        gt=0,
        description="s, window of the cubic fit differentiating the odometer "
        "(a noise-free odometer needs no smoothing: set it small)",
    )
    inc_rate_window: float = Field(
        1.0, gt=0, description="Savitzky–Golay window of the İ smoothing, s"
    )
    max_misalignment: float = Field(
        60.0, gt=0, lt=90, description="|δ| above which a sample is flagged, deg"
    )
    closure: bool = Field(True, description="remove the misclosure linearly in time")
    passes: int = Field(
        2, ge=1, le=5, description="passes removing the tool's acceleration (1: along-axis only)"
    )
    gyro_axes: Literal["auto", "x", "xy", "xyz"] = Field(
        "auto",
        description="gyro axes to integrate (pipeline.continuous.multiaxis): x servo'd "
        "single-axis, xy two-axis (high side from the toolface), xyz strapdown attitude; "
        "auto: every gyro column present",
    )
    # error magnitudes (1σ) of the predicted sigma_azi / sigma_inc (continuous.sigma);
    # defaults: the mems-vrg tool of seed 004 (docs/simulator.md)
    gyro_arw: float = Field(0.02, ge=0, description="gyro angle random walk, deg/√h")
    gyro_bias: float = Field(
        5.0, ge=0, description="gyro bias not calibrated out (turn-on bias), deg/h"
    )
    gyro_bias_trend: float = Field(0.5, ge=0, description="gyro bias trend, (deg/h)/h")
    gyro_bias_instability: float = Field(
        0.1, ge=0, description="gyro bias instability (Gauss–Markov σ), deg/h"
    )
    gyro_correlation_time: float = Field(
        300.0, gt=0, description="correlation time of the bias instability, s"
    )
    gyro_rate_random_walk: float = Field(0.0, ge=0, description="gyro rate random walk, (deg/h)/√h")
    gyro_scale_factor: float = Field(300.0, ge=0, description="gyro scale-factor error, ppm")
    gyro_g_sensitivity: float = Field(0.1, ge=0, description="gyro g-dependent bias, (deg/h)/g")
    gyro_misalignment: float = Field(1.0, ge=0, description="gyro input-axis misalignment, mrad")
    acc_noise: float = Field(0.006, ge=0, description="accelerometer VRW, (m/s)/√h")
    acc_bias: float = Field(2.0e-3, ge=0, description="accelerometer bias, m/s²")
    acc_misalignment: float = Field(
        0.5, ge=0, description="accelerometer triad misalignment to the gyro frame, mrad"
    )
    odometer_noise: float = Field(0.05, ge=0, description="odometer noise per sample, m")
