"""Cost of contract checking relative to the stage it guards, on a 1M-row table.

Runs the minimum-curvature stage on 1,000 surveys × 1,000 stations (1M rows) and checks its
input (Stations) and output (Trajectory) contracts, as the runner does at each boundary.
Target: checks ≤ 5 % of the stage's run time.

    python benchmarks/bench_contracts.py
"""

from __future__ import annotations

import sys
import timeit

import numpy as np
import pyarrow as pa

from pipeline.stages.survey import MinCurveParams, min_curve
from pipeline.tables import Stations, Trajectory

SURVEYS, STATIONS = 1_000, 1_000


def stations_table() -> pa.Table:
    rng = np.random.default_rng(1)
    md = np.tile(np.arange(STATIONS) * 30.0, SURVEYS)
    inc = np.clip(np.cumsum(rng.normal(0.5, 0.5, (SURVEYS, STATIONS)), axis=1), 0, 120)
    azi = np.cumsum(rng.normal(0.0, 1.0, (SURVEYS, STATIONS)), axis=1) % 360
    survey = np.repeat([f"s{i:04d}" for i in range(SURVEYS)], STATIONS)
    return Stations.compiled().make_table(
        {"survey": survey, "md": md, "inc": inc.ravel(), "azi": azi.ravel()},
        north_reference="true",
    )


def best(fn: object, repeat: int = 5) -> float:
    return min(timeit.repeat(fn, number=1, repeat=repeat))  # type: ignore[arg-type]


def main() -> int:
    stations = stations_table()
    params = MinCurveParams()
    trajectory = min_curve({"stations": stations}, params, None)["trajectory"]  # type: ignore[arg-type]
    stage = best(lambda: min_curve({"stations": stations}, params, None))  # type: ignore[arg-type]
    check_in = best(lambda: Stations.validate_table(stations))
    check_out = best(lambda: Trajectory.validate_table(trajectory))
    share = (check_in + check_out) / stage
    print(f"rows: {stations.num_rows:,}")
    print(f"minimum_curvature stage: {stage * 1e3:8.1f} ms")
    n_in, n_out = len(Stations.compiled().columns), len(Trajectory.compiled().columns)
    print(f"input contract (Stations, {n_in} cols): {check_in * 1e3:8.1f} ms")
    print(f"output contract (Trajectory, {n_out} cols): {check_out * 1e3:8.1f} ms")
    print(f"contract checks / stage time: {share:.1%} (target <= 5%)")
    return 0 if share <= 0.05 else 1


if __name__ == "__main__":
    sys.exit(main())
