"""Continuous (moving) gyro surveys: azimuth integration between two compassing stops.

Modules, each importing only those above it: ``tables`` (output contracts, flag bits),
``options``, ``run`` (run bounds, stops, odometer fit), ``sigma`` (predicted errors),
``stations`` (series and resampled stations), ``multiaxis`` and ``strapdown`` (two- and
three-axis tools), ``integrate`` (single-axis integration and the dispatch by tool).
"""

from pipeline.continuous.integrate import integrate_continuous
from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.run import ContinuousError
from pipeline.continuous.stations import ContinuousResult
from pipeline.continuous.tables import (
    FLAG_AFTER_VERTICAL,
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_LARGE_MISALIGNMENT,
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
    ContinuousSeries,
    ContinuousStations,
)

__all__ = [
    "FLAG_AFTER_VERTICAL",
    "FLAG_AZIMUTH_UNDEFINED",
    "FLAG_LARGE_MISALIGNMENT",
    "FLAG_NEAR_VERTICAL",
    "FLAG_NO_CLOSURE",
    "ContinuousError",
    "ContinuousOptions",
    "ContinuousResult",
    "ContinuousSeries",
    "ContinuousStations",
    "integrate_continuous",
]
