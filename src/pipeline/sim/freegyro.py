"""Free-gyro surveys: azimuth readings whose error drifts in time (DOMAIN.md §4).

A free (directional) gyro is oriented at the wellhead; its azimuth reading then drifts:
ΔA(t) = offset + rate·t + curvature·t² (t in hours from the start of the run), plus a random
reading error. The run goes down the stations (in-run) and, optionally, back up (out-run),
stopping ``dwell`` seconds for each reading and travelling at ``speed`` between them.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pipeline.sim.spec import Drift, FreeGyroSurvey, SimulationSpec
from pipeline.tables import FreeGyroReadings


def drift_error(drift: Drift, hours: np.ndarray) -> np.ndarray:
    """Azimuth error of a free gyro after ``hours`` of running, deg."""
    return drift.offset + drift.rate * hours + drift.curvature * hours**2


def simulate_free_gyro(spec: SimulationSpec) -> pa.Table:
    """Readings of a free-gyro survey (azimuths true north plus drift and noise)."""
    survey = spec.survey
    if not isinstance(survey, FreeGyroSurvey):
        raise TypeError("simulate_free_gyro() runs free_gyro surveys")
    rng = np.random.default_rng(spec.seed)
    path = spec.path()
    down = np.arange(path.start_md, path.end_md + 1e-9, survey.every)
    mds = np.concatenate([down, down[::-1][1:]]) if survey.out_run else down
    run = np.where(np.arange(len(mds)) < len(down), "in", "out")
    travel = np.concatenate([[0.0], np.abs(np.diff(mds)) / survey.speed])
    # each reading is taken at the middle of its dwell
    time = np.cumsum(travel) + survey.dwell * (np.arange(len(mds)) + 0.5)
    state = path.evaluate(mds)
    true_inc, true_azi = np.degrees(state.inc), np.degrees(state.azi) % 360.0
    error = drift_error(survey.drift, time / 3600.0)
    azimuth = (true_azi + error + rng.normal(0.0, survey.reading_noise, len(mds))) % 360.0
    inc = np.abs(true_inc + rng.normal(0.0, survey.inclination_noise, len(mds)))
    return FreeGyroReadings.compiled().make_table(
        {
            "run": run,
            "station": np.concatenate([np.arange(len(down)), np.arange(len(down) - 2, -1, -1)])
            if survey.out_run
            else np.arange(len(down)),
            "time": time,
            "md": mds,
            "inc": np.minimum(inc, 180.0),
            "azi": azimuth,
            "true_inc": true_inc,
            "true_azi": true_azi,
        },
        north_reference="true",
    )
