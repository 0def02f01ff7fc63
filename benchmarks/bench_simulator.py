"""Simulator speed: one hour of 100 Hz raw samples (continuous survey at 1 m/s).

Issue target: well under 2 s. There is no open-source peer that simulates gyro survey
tools, so this reports absolute time and samples per second.

    python benchmarks/bench_simulator.py
"""

from __future__ import annotations

import sys
import timeit

from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec

SPEC = SimulationSpec.model_validate(
    {
        "name": "hour",
        "site": {
            "latitude": 61.25,
            "date": "2026-11-21",
            "magnetic": {"total_field": 59731, "dip": 78.29, "declination": 17.0},
        },
        "well": {
            "sections": [
                {"kind": "vertical", "length": 500},
                {"kind": "build", "dls": 2.0, "inc": 45, "azi": 37},
                {"kind": "hold", "to_md": 4000},
            ]
        },
        "tool": {"preset": "mems-vrg"},
        # 3,285 m at 1 m/s plus two 5-position stops ≈ 3,600 s
        "survey": {"mode": "continuous", "start_md": 200, "end_md": 3485, "speed": 1.0},
    }
)


def main() -> int:
    result = simulate(SPEC)
    rows = result.samples.num_rows
    best = min(timeit.repeat(lambda: simulate(SPEC), number=1, repeat=3))
    print(f"samples: {rows:,} ({rows / 100 / 3600:.2f} h at 100 Hz)")
    print(f"simulate(): {best:.2f} s ({rows / best / 1e6:.2f} M samples/s); target < 2 s")
    return 0 if best < 2.0 else 1


if __name__ == "__main__":
    sys.exit(main())
