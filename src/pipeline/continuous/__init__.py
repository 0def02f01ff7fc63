"""Continuous (moving) gyro surveys: azimuth integration between two compassing stops.

Modules, each importing only those above it: ``tables`` (output contracts, flag bits),
``options``, ``filters`` (Savitzky–Golay and convolutions in NumPy), ``store`` (the run's
columns on disk, chunks and carried state), ``run`` (run bounds, stops, odometer fit),
``sigma_noise`` and ``sigma`` (predicted errors), ``series`` (the stored run read back, the
full-rate series stream), ``stations`` (resampled stations), ``multiaxis`` and
``strapdown`` (two- and three-axis tools), ``integrate`` (single-axis integration and the
dispatch by tool).

Any survey length in bounded memory (issue #20): the samples (a table or a stream of record
batches) are written once to a column store (on disk past 24 MiB), and every pass —
odometer fit, the integration's passes, station extraction, the σ budget — reads a chunk of
rows plus the overlap its filters need, carrying running sums, the last azimuth and the
Newton solver's first guess from chunk to chunk; the results equal those of the whole series
in one chunk within the rounding of its FFT blocks and segment sums (1e-9° checked,
tests/continuous/test_chunks.py). A three-axis (strapdown) run still reads its
span whole.

The names below load their module on first use, so that importing a submodule (as the
stage plugin does to register) does not load the integration.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pipeline.lazy import lazy_names

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
        FLAG_SHORT_STOP,
        ContinuousSeries,
        ContinuousStations,
    )

_HOMES = {
    "pipeline.continuous.integrate": ("integrate_continuous",),
    "pipeline.continuous.options": ("ContinuousOptions",),
    "pipeline.continuous.run": ("ContinuousError",),
    "pipeline.continuous.stations": ("ContinuousResult",),
    "pipeline.continuous.tables": (
        "FLAG_AFTER_VERTICAL",
        "FLAG_AZIMUTH_UNDEFINED",
        "FLAG_LARGE_MISALIGNMENT",
        "FLAG_NEAR_VERTICAL",
        "FLAG_NO_CLOSURE",
        "FLAG_SHORT_STOP",
        "FLAG_SHORT_STOP",
        "ContinuousSeries",
        "ContinuousStations",
    ),
}

__all__ = [
    "FLAG_AFTER_VERTICAL",
    "FLAG_AZIMUTH_UNDEFINED",
    "FLAG_LARGE_MISALIGNMENT",
    "FLAG_NEAR_VERTICAL",
    "FLAG_NO_CLOSURE",
    "FLAG_SHORT_STOP",
    "ContinuousError",
    "ContinuousOptions",
    "ContinuousResult",
    "ContinuousSeries",
    "ContinuousStations",
    "integrate_continuous",
]


__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
