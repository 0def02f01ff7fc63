"""Gyrocompassing speed: stations compassed per second from raw samples.

A simulated point survey (MEMS single-axis tool, 100 Hz, five positions × 40 s per station,
60 stations) is reduced to position readings and compassed; the time of those two steps
(not the simulation) gives stations per second. No open-source peer compasses gyro data, so
this reports absolute throughput.

    python benchmarks/bench_compass.py
"""

from __future__ import annotations

import sys
import timeit

from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.readings import position_readings
from pipeline.gyrocompass.solve import compass
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec

SPEC = SimulationSpec.model_validate(
    {
        "name": "bench",
        "site": {"latitude": 61.25, "date": "2026-11-21"},
        "well": {
            "sections": [
                {"kind": "vertical", "length": 300},
                {"kind": "build", "dls": 3.0, "inc": 50, "azi": 120},
                {"kind": "hold", "to_md": 1800},
            ]
        },
        "tool": {"preset": "mems-vrg"},
        "survey": {"mode": "point", "every": 30, "dwell": 40, "move_time": 3},
    }
)


def main() -> int:
    samples = simulate(SPEC).samples
    options = CompassOptions()

    def run() -> int:
        readings = position_readings(samples)
        stations, _ = compass(readings, 61.25, options)
        return int(stations.num_rows)

    n = run()
    best = min(timeit.repeat(run, number=1, repeat=5))
    print(f"raw samples: {samples.num_rows:,} at 100 Hz; stations: {n}")
    print(
        f"readings + compass: {best * 1e3:.1f} ms → {n / best:,.0f} stations/s "
        f"({samples.num_rows / best / 1e6:.1f} M samples/s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
