"""Continuous (moving) gyro surveys: azimuth integration between two compassing stops.

Modules, each importing only those above it: ``tables`` (output contracts, flag bits),
``options``, ``run`` (run bounds, stops, odometer fit), ``sigma`` (predicted errors),
``stations`` (series and resampled stations), ``multiaxis`` and ``strapdown`` (two- and
three-axis tools), ``integrate`` (single-axis integration and the dispatch by tool).

The names below load their module on first use, so that importing a submodule (as the
stage plugin does to register) does not load the integration and SciPy's signal package.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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

_HOME_OF = {
    "integrate_continuous": "pipeline.continuous.integrate",
    "ContinuousOptions": "pipeline.continuous.options",
    "ContinuousError": "pipeline.continuous.run",
    "ContinuousResult": "pipeline.continuous.stations",
    **{
        name: "pipeline.continuous.tables"
        for name in (
            "FLAG_AFTER_VERTICAL",
            "FLAG_AZIMUTH_UNDEFINED",
            "FLAG_LARGE_MISALIGNMENT",
            "FLAG_NEAR_VERTICAL",
            "FLAG_NO_CLOSURE",
            "ContinuousSeries",
            "ContinuousStations",
        )
    },
}

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


def __getattr__(name: str) -> Any:
    module = _HOME_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'pipeline.continuous' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
