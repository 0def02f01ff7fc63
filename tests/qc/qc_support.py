"""Simulated point surveys for the validity-check tests: random wells, readings, the site."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from tests_support import read_stations

MAGNETIC = {"total_field": 59731.0, "dip": 78.29, "declination": 17.0}
SITE = {"latitude": 61.25, "longitude": 73.4, "date": "2026-11-21", "magnetic": MAGNETIC}
TRIM = ReadingOptions(trim_start=0.5, min_dwell=1.0)
FOUR_STOPS = """name: {name}
seed: 3
site:
  latitude: 61.25
  longitude: 73.4
  elevation: 54.3
  date: 2026-11-21
tool: {{preset: mems-vrg}}
well:
  sections:
    - {{kind: vertical, length: 50}}
    - {{kind: build, dls: 6.0, inc: 30, azi: 37}}
    - {{kind: hold, to_md: 300}}
survey: {{mode: point, every: 100, positions: [0, 90, 180, 270, 0], dwell: 10}}
"""
"""A simulation plan (``name`` to fill in): a point survey with stops at MD 0, 100, 200
and 300 m, five frame positions of 10 s each."""


def random_well(path: Path, n: int, seed: int, inc: tuple[float, float] = (5, 120)) -> Path:
    """Stations 30 m apart at random attitudes (after a vertical first station)."""
    rng = np.random.default_rng(seed)
    rows = zip(rng.uniform(*inc, n), rng.uniform(0, 360, n), strict=True)
    path.write_text(
        "MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n"
        + "\n".join(f"{30 * (i + 1)},{a:.4f},{b:.4f}" for i, (a, b) in enumerate(rows))
        + "\n"
    )
    return path


def point_run(
    well: Path,
    tool: dict[str, Any],
    *,
    positions=(0, 90, 180, 270, 0),
    seed: int = 1,
    site: dict[str, Any] | None = None,
    dwell: float = 2.0,
):
    """Simulate a point survey of the ideal tool with ``tool`` overrides; return the
    simulation, its position readings and the site."""
    spec = SimulationSpec.model_validate(
        {
            "name": "qc",
            "seed": seed,
            "site": site or SITE,
            "well": {"stations": str(well)},
            "tool": {"preset": "ideal", "overrides": tool},
            "survey": {
                "mode": "point",
                "every": 30,
                "dwell": dwell,
                "move_time": 1.0,
                "settle_time": 0.5,
                "speed": 30.0,
                "positions": list(positions),
            },
        }
    )
    spec.well.load(read_stations)
    sim = simulate(spec)
    return sim, position_readings(sim.samples, TRIM), spec.site
