"""Simulated in-run and out-run stations of one gyro survey, for the acceptance-gate and
definitive-survey tests (simulated once per session).

The simulator runs the same well twice with a navigation-grade gyro (raw samples, compassed
into stations): an in-run (seed 4) and an out-run (seed 5) that agree within the industry's
gates. A second out-run has g-sensitive x and y gyros (0.3 °/h/g along their own axes):
compassing does not remove that bias (it turns with the frame like the Earth rate it
measures), so its azimuths err by up to ~2° at the inclined stations (61° N) — beyond the
1° gate — while inclination and depth still agree.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import pandas as pd

import pipeline as gp

PLAN: dict[str, Any] = {
    "name": "inout",
    "site": {"latitude": 61.25, "longitude": 73.4, "elevation": 54.3, "date": "2026-11-21"},
    "well": {
        "sections": [
            {"kind": "vertical", "length": 120},
            {"kind": "build", "dls": 3.0, "inc": 35, "azi": 60},
            {"kind": "hold", "to_md": 900},
        ]
    },
    "survey": {
        "mode": "point",
        "every": 60,
        "positions": [0, 90, 180, 270, 0],
        "dwell": 8,
        "speed": 5.0,
    },
}
G_SENSITIVE = {"gyro": {"g_sensitivity": [[0.3, 0, 0], [0, 0.3, 0], [0, 0, 0]]}}


def _stations(seed: int, **overrides: Any) -> pd.DataFrame:
    plan = {**PLAN, "seed": seed, "tool": {"preset": "nav-grade", "overrides": overrides}}
    samples = gp.simulate(plan).samples
    stations = gp.compass(gp.position_readings(samples, trim_start=1.0)).stations
    assert isinstance(stations, pd.DataFrame)
    return stations[["md", "inc", "azi"]].copy()


@cache
def _runs() -> dict[str, pd.DataFrame]:
    return {"in": _stations(4), "out": _stations(5), "bad": _stations(5, **G_SENSITIVE)}


def simulated_runs() -> dict[str, pd.DataFrame]:
    """``in``, ``out`` (agreeing) and ``bad`` (azimuth error) stations, fresh copies."""
    return {name: table.copy() for name, table in _runs().items()}
