"""gyropipe: gyroscopic well-survey processing as a DAG of pluggable stages over Arrow tables.

The Python API (``import pipeline as gp``)::

    stations = gp.read("survey.csv")                  # DataFrame, units in .attrs
    trajectory = gp.minimum_curvature(stations, vs_azimuth=37.5)
    result = gp.run("pipelines/point-gyro.yaml", {"samples": "well-1.mcap"})
    report = gp.run_batch("pipelines/survey.yaml", "wells/*.csv", out="out")  # many wells
    page = gp.fleet_page("out")                       # out/fleet.html: every well on a page
    result.frame("trajectory.trajectory")

Functions take pandas DataFrames or Arrow tables and return the same kind; units are
canonical (m, deg, deg/h, m/s², nT, s) unless a table declares others, which are converted
(:mod:`pipeline.api.frames`). Everything not listed in ``__all__`` is internal. Plugin
authors import from :mod:`pipeline.plugin`.

Names are loaded on first use, so ``import pipeline`` (and the command line) stays fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pipeline.lazy import lazy_names
from pipeline.version import __version__

if TYPE_CHECKING:
    from pipeline.api.batch import fleet_page, run_batch
    from pipeline.api.clearance import clearance
    from pipeline.api.frames import TableLike, to_frame, to_table
    from pipeline.api.functions import (
        Tables,
        calibrate_drift,
        compass,
        correct_drift,
        integrate_continuous,
        interpolate,
        minimum_curvature,
        position_readings,
        position_uncertainty,
        read,
        read_table,
        report,
        simulate,
        survey_method,
        validity_checks,
        write,
    )
    from pipeline.api.plots import plot_plan, plot_section
    from pipeline.api.run import RunResult, run
    from pipeline.api.runs import acceptance_gates, definitive_survey
    from pipeline.batch.run import BatchReport
    from pipeline.errors import GyropipeError
    from pipeline.well import WellMetadata

_HOMES = {
    "pipeline.api.batch": ("fleet_page", "run_batch"),
    "pipeline.api.clearance": ("clearance",),
    "pipeline.api.frames": ("TableLike", "to_frame", "to_table"),
    "pipeline.api.functions": (
        "Tables",
        "calibrate_drift",
        "compass",
        "correct_drift",
        "integrate_continuous",
        "interpolate",
        "minimum_curvature",
        "position_readings",
        "position_uncertainty",
        "read",
        "read_table",
        "report",
        "simulate",
        "survey_method",
        "validity_checks",
        "write",
    ),
    "pipeline.api.plots": ("plot_plan", "plot_section"),
    "pipeline.api.run": ("RunResult", "run"),
    "pipeline.api.runs": ("acceptance_gates", "definitive_survey"),
    "pipeline.batch.run": ("BatchReport",),
    "pipeline.errors": ("GyropipeError",),
    "pipeline.well": ("WellMetadata",),
}

__all__ = [
    "BatchReport",
    "GyropipeError",
    "RunResult",
    "TableLike",
    "Tables",
    "WellMetadata",
    "__version__",
    "acceptance_gates",
    "calibrate_drift",
    "clearance",
    "compass",
    "correct_drift",
    "definitive_survey",
    "fleet_page",
    "integrate_continuous",
    "interpolate",
    "minimum_curvature",
    "plot_plan",
    "plot_section",
    "position_readings",
    "position_uncertainty",
    "read",
    "read_table",
    "report",
    "run",
    "run_batch",
    "simulate",
    "survey_method",
    "to_frame",
    "to_table",
    "validity_checks",
    "write",
]


__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
