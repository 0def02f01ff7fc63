"""Magnetometer-bias diagnosis: is each estimate within 3 of its stated σ? (issue 29 item 8)

Run from the repository root::

    .venv/bin/python benchmarks/study_magnetic_sigma.py [--presets mems-vrg,dtg-xy,nav-grade]
        [--seeds 1,2,3]

For every tool preset, seed, magnetometer axis and sign, simulates a point survey of
``examples/stations-j-well.csv`` every 60 m (the preset's own sensor errors; 800 nT on that
axis, 2 nT/√Hz magnetometer noise) and runs it through the public API (``gp.simulate`` →
``gp.position_readings`` → ``gp.validity_checks``, the stage taking the accelerometer error
magnitudes from the well's tool_preset). Prints each estimate, its stated σ and
z = (estimate − injected)/σ, and the largest |z| per preset. The test
tests/qc/test_magnetic_sigma.py runs six of these cases.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path[:0] = [str(TESTS), str(TESTS / "qc")]
from test_magnetic_sigma import BIAS, estimate  # noqa: E402


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", default="mems-vrg,dtg-xy,nav-grade")
    parser.add_argument("--seeds", default="1,2,3")
    args = parser.parse_args(argv)
    for preset in args.presets.split(","):
        worst = 0.0
        for seed in (int(s) for s in re.split(r"[, ]+", args.seeds)):
            for axis in "xyz":
                for sign in (1, -1):
                    named, value, sigma = estimate(preset, axis, sign * BIAS, seed)
                    z = (value - sign * BIAS) / sigma
                    worst = max(worst, abs(z)) if named == axis else float("inf")
                    print(
                        f"{preset:10s} seed {seed} {axis} {sign * BIAS:+6.0f} nT → mag {named} "
                        f"{value:+8.1f} ± {sigma:.2g} nT  z {z:+.2f}",
                        flush=True,
                    )
        print(f"{preset}: largest |z| {worst:.2f}", flush=True)


if __name__ == "__main__":
    main()
