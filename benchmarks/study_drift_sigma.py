"""Free-gyro tie-in correction with σ_r estimated: is the stated σ the error's scatter?

Run from the repository root (any tree: ``PYTHONPATH=OLD/src`` for an older one)::

    .venv/bin/python benchmarks/study_drift_sigma.py [--runs 1000] [--to-md 1200]
        [--bad 2.4 --bad-station 1]

Simulates ``examples/plans/j-well-free-gyro.yaml`` (seeds 0…runs − 1; ``--to-md`` ends its
hold section there, ``--bad`` adds that many degrees to one station's out-run azimuth),
corrects each survey from its tie-in misclosure with σ_r estimated from the in/out pairs
and the true azimuth at the tie-in as reference, and prints: the pairs, the mean of
σ̂_r²/σ_r² (± its standard error), the correlation of σ̂_r² with the rate's |error|, and
for the rate and for three corrected azimuths (rows 15, 40 and the 20th from the end) the
std of error/stated σ and the share within ±1.96 stated σ.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pyarrow as pa
import yaml

from pipeline.drift.correction import CorrectionOptions, correct_survey
from pipeline.sim.freegyro import simulate_free_gyro
from pipeline.sim.spec import FreeGyroSurvey, SimulationSpec

PLAN = Path(__file__).resolve().parents[1] / "examples" / "plans" / "j-well-free-gyro.yaml"


def survey(seed: int, to_md: float | None, bad: float, bad_station: int) -> pa.Table:
    """One simulated survey of the plan (seed, hold end, one bad out-run azimuth)."""
    plan = yaml.safe_load(PLAN.read_text())
    plan["seed"] = seed
    if to_md is not None:
        plan["well"]["sections"][-1]["to_md"] = to_md
    readings = simulate_free_gyro(SimulationSpec.model_validate(plan))
    if bad:
        run = np.array(readings.column("run").to_pylist())
        station = readings.column("station").to_numpy()
        azi = readings.column("azi").to_numpy().copy()
        row = int(np.flatnonzero((run == "out") & (station == bad_station))[0])
        azi[row] = (azi[row] + bad) % 360.0
        field = readings.schema.field("azi")
        readings = readings.set_column(readings.column_names.index("azi"), field, pa.array(azi))
    return readings


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--to-md", type=float, default=None, help="end of the hold, m")
    parser.add_argument("--bad", type=float, default=0.0, help="deg added to one reading")
    parser.add_argument("--bad-station", type=int, default=1)
    args = parser.parse_args(argv)
    plan = SimulationSpec.model_validate(yaml.safe_load(PLAN.read_text())).survey
    assert isinstance(plan, FreeGyroSurvey)
    noise, rate = plan.reading_noise, plan.drift.rate
    ratio, err, z_rate, z_azi = [], [], [], []
    for seed in range(args.runs):
        readings = survey(seed, args.to_md, args.bad, args.bad_station)
        ref = readings.column("true_azi")[0].as_py()
        out = correct_survey(readings, CorrectionOptions(reference_azimuth=ref))
        ratio.append((out.reading_sigma / noise) ** 2)
        err.append(abs(out.rate.rate - rate))
        z_rate.append((out.rate.rate - rate) / out.rate.sigma)
        error = out.readings.column("azi").to_numpy() - readings.column("true_azi").to_numpy()
        rows = [15, 40, readings.num_rows - 20]
        sigma = out.readings.column("sigma_azi").to_numpy()[rows]
        z_azi.extend(((error[rows] + 180.0) % 360.0 - 180.0) / sigma)
    print(
        f"{out.qc.num_rows} pairs, {args.runs} surveys: σ̂²/σ² {np.mean(ratio):.3f} "
        f"± {np.std(ratio) / np.sqrt(args.runs):.3f}, corr(σ̂², |rate error|) "
        f"{np.corrcoef(ratio, err)[0, 1]:+.2f}"
    )
    for name, z in (("rate", np.array(z_rate)), ("azimuths", np.array(z_azi))):
        print(
            f"  {name:8s}: std(error/σ) {np.std(z):.3f}, within ±1.96 σ "
            f"{np.mean(np.abs(z) < 1.96):.3f}"
        )


if __name__ == "__main__":
    main()
