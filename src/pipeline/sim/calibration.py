"""Calibration of a free-gyro inclinometer's azimuth channel (seed 000): ``series`` sweeps of
the set azimuths, one after another, each reading taken ``reading_interval`` s after the
previous one and ``series_gap`` s between series.

The reading at set azimuth α and time t (s from the start) is
``α + Σ_k a_k sin(k·α + φ_k) + ΔA(t) + ε`` (mod 360°): an azimuth-dependent systematic
error (harmonics of the set azimuth), the drift ΔA(t) = offset + rate·t + curvature·t²
(t in hours, :class:`~pipeline.sim.spec.Drift`) and a random reading error ε ~ N(0, σ²)
(seed 000: ±5…10° per reading for this class of instrument). Angles in degrees.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from pipeline.drift.calibration import FloatArray
from pipeline.drift.tables import CalibrationReadings
from pipeline.sim.freegyro import drift_error
from pipeline.sim.spec import Drift

PAPER_AZIMUTHS = tuple(float(a) for a in range(0, 361, 30))
"""Set azimuths of seed 000's sweeps: 0°, 30°, …, 360° (13 readings per series)."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Harmonic(_Strict):
    """One term a·sin(k·α + φ) of the azimuth-dependent systematic error."""

    order: int = Field(ge=1, description="k, multiple of the set azimuth")
    amplitude: float = Field(description="a, deg")
    phase: float = Field(0.0, description="φ, deg")


class CalibrationPlan(_Strict):
    """What the calibration simulator does (times in s, angles in deg)."""

    instrument: str = Field("IG50-0417", description="instrument serial")
    series: int = Field(4, ge=1, description="number of series")
    set_azimuths: tuple[float, ...] = Field(
        PAPER_AZIMUTHS, min_length=1, description="set azimuths of one sweep, deg, in order"
    )
    sweep: Literal["forward", "alternate"] = Field(
        "forward", description="every series in the same order, or every other one reversed"
    )
    reading_interval: float = Field(60.0, gt=0, description="time between readings, s")
    series_gap: float = Field(120.0, ge=0, description="pause between series, s")
    reading_noise: float = Field(5.0, ge=0, description="σ of a reading's random error, deg")
    systematic: tuple[Harmonic, ...] = Field(
        (Harmonic(order=1, amplitude=3.0, phase=20.0), Harmonic(order=2, amplitude=1.5)),
        description="harmonics of the azimuth-dependent systematic error",
    )
    drift: Drift = Field(
        default_factory=lambda: Drift(offset=0.0, rate=4.0),
        description="drift ΔA(t) = offset + rate·t + curvature·t², t in h",
    )
    seed: int = Field(0, description="random seed")


def systematic_error(harmonics: tuple[Harmonic, ...], azimuth: FloatArray) -> FloatArray:
    """Azimuth-dependent systematic error (deg) at set azimuths (deg)."""
    alpha = np.radians(azimuth)
    total: FloatArray = np.zeros_like(alpha)
    for h in harmonics:
        total += h.amplitude * np.sin(h.order * alpha + np.radians(h.phase))
    return total


def schedule(plan: CalibrationPlan) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """Series number (1-based), set azimuth (deg) and time (s) of every reading."""
    sweep = np.asarray(plan.set_azimuths, dtype=float)
    per_series = len(sweep)
    series = np.repeat(np.arange(1, plan.series + 1), per_series)
    azimuths = np.concatenate(
        [sweep[::-1] if plan.sweep == "alternate" and i % 2 else sweep for i in range(plan.series)]
    )
    slot = np.tile(np.arange(per_series), plan.series)
    period = per_series * plan.reading_interval + plan.series_gap
    time = (series - 1) * period + (slot + 0.5) * plan.reading_interval
    return series, azimuths, time


def simulate_calibration(plan: CalibrationPlan) -> pa.Table:
    """A :class:`~pipeline.drift.tables.CalibrationReadings` table (measured azimuths and
    times) of the plan; the same seed gives the same readings."""
    rng = np.random.default_rng(plan.seed)
    series, azimuths, time = schedule(plan)
    error = (
        systematic_error(plan.systematic, azimuths)
        + drift_error(plan.drift, time / 3600.0)
        + rng.normal(0.0, plan.reading_noise, len(time))
    )
    return CalibrationReadings.compiled().make_table(
        {
            "instrument": [plan.instrument] * len(time),
            "series": series,
            "set_azimuth": azimuths,
            "measured_azimuth": (azimuths + error) % 360.0,
            "time": time,
        }
    )
