"""Shared by the continuous-mode tests: the site, the compassed stops of a simulated run, and
an integrated run's errors against the simulator's truth."""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pipeline.continuous import ContinuousResult
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.gyrocompass.solve import compass
from pipeline.sim.simulate import Simulation
from pipeline.sim.spec import SimulationSpec
from pipeline.survey.mincurve import minimum_curvature

LAT = 61.25
SITE = {"latitude": LAT, "longitude": 73.4, "elevation": 120.0, "date": "2026-11-21"}


def compassed(
    samples: pa.Table, options: CompassOptions | None = None
) -> tuple[pa.Table, pa.Table, pa.Table]:
    """Position readings, compassed stops and rejects of a simulated run's samples (noise
    floor 0.01 °/h unless ``options`` say otherwise)."""
    readings = position_readings(samples, ReadingOptions(trim_start=0.5, min_dwell=1.0))
    stops, rejects = compass(readings, LAT, options or CompassOptions(noise_floor=0.01))
    return readings, stops, rejects


def azimuth_error(result: ContinuousResult, sim: Simulation) -> tuple[np.ndarray, np.ndarray]:
    """Integrated minus true azimuth (deg, wrapped to ±180) and the flags, per series sample."""
    series = result.series.read_all()
    truth_t = sim.truth.column("time").to_numpy()
    t = series.column("time").to_numpy()
    rows = np.searchsorted(truth_t, t)
    assert np.allclose(truth_t[rows], t)
    err = series.column("azi").to_numpy() - sim.truth.column("azi").to_numpy()[rows]
    return (err + 180) % 360 - 180, series.column("flags").to_numpy()


def position_error(result: ContinuousResult, spec: SimulationSpec) -> np.ndarray:
    """Minimum-curvature positions of the stations, tied at the first one's true position,
    minus the truth: (stations, 3) N, E, TVD in m."""
    stations = result.stations
    md = stations.column("md").to_numpy()
    truth = spec.path().evaluate(md)
    mc = minimum_curvature(
        md,
        np.radians(stations.column("inc").to_numpy()),
        np.radians(stations.column("azi").to_numpy()),
        tie_north=truth.position[0, 0],
        tie_east=truth.position[0, 1],
        tie_tvd=truth.position[0, 2],
    )
    error: np.ndarray = np.stack([mc.north, mc.east, mc.tvd], -1) - truth.position
    return error
