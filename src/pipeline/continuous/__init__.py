"""Continuous (moving) gyro surveys: azimuth integration between two compassing stops."""

from pipeline.continuous.integrate import (
    ContinuousOptions,
    ContinuousResult,
    ContinuousSeries,
    ContinuousStations,
    integrate_continuous,
)

__all__ = [
    "ContinuousOptions",
    "ContinuousResult",
    "ContinuousSeries",
    "ContinuousStations",
    "integrate_continuous",
]
