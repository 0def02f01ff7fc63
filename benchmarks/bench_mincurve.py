"""Benchmark the batched minimum-curvature core against wellpathpy and welleng.

Run from the repository root: ``python benchmarks/bench_mincurve.py [--repeat N] [--seed S]``.
Prints, per case, the best-of-N time of one call of each implementation, the speed-up of ours
over the fastest peer, and the largest station-position difference to each peer. Exits with
status 1 if any peer disagrees by more than 1e-6 m.
"""

from __future__ import annotations

import argparse
import sys
import timeit
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib.metadata import version

import numpy as np
import wellpathpy.mincurve as wpp  # type: ignore[import-untyped]
from numpy.typing import NDArray
from welleng.utils import MinCurve, min_curve_step

from pipeline.survey.mincurve import minimum_curvature

Floats = NDArray[np.float64]
TOLERANCE_M = 1e-6


@dataclass(frozen=True)
class Survey:
    """One survey; angles in degrees (wellpathpy) and radians (ours, welleng)."""

    md: Floats
    inc_deg: Floats
    azi_deg: Floats

    @property
    def inc(self) -> Floats:
        return np.radians(self.inc_deg)

    @property
    def azi(self) -> Floats:
        return np.radians(self.azi_deg)


def make_survey(rng: np.random.Generator, n: int) -> Survey:
    """Smooth random well: ~30 m MD steps, doglegs of a few degrees per step."""
    md = rng.uniform(0.0, 500.0) + np.cumsum(rng.uniform(25.0, 35.0, n))
    inc = np.clip(np.abs(rng.uniform(0, 30) + np.cumsum(rng.normal(0.3, 1.0, n))), 0.0, 175.0)
    azi = np.mod(rng.uniform(0, 360) + np.cumsum(rng.normal(0.0, 2.0, n)), 360.0)
    return Survey(md, inc, azi)


def ours(surveys: Sequence[Survey]) -> Callable[[], Floats]:
    """One batched call over all surveys; returns (n, 3) N, E, TVD."""
    md = np.concatenate([s.md for s in surveys])
    inc = np.concatenate([s.inc for s in surveys])
    azi = np.concatenate([s.azi for s in surveys])
    offsets = np.concatenate([[0], np.cumsum([s.md.size for s in surveys])])

    def run() -> Floats:
        r = minimum_curvature(md, inc, azi, offsets=offsets)
        return np.stack([r.north, r.east, r.tvd], axis=-1)

    return run


def wellpathpy_loop(surveys: Sequence[Survey]) -> Callable[[], Floats]:
    """One call per survey (degrees); each survey starts at (0, 0, 0) like ours."""

    def run() -> Floats:
        out = [wpp.minimum_curvature(s.md, s.inc_deg, s.azi_deg) for s in surveys]
        return np.concatenate([np.stack([n, e, tvd], axis=-1) for tvd, n, e, _ in out])

    return run


def welleng_loop(surveys: Sequence[Survey]) -> Callable[[], Floats]:
    """One ``MinCurve`` per survey (radians); ``frame="nev"`` gives [N, E, TVD] columns."""
    inputs = [(s.md, s.inc, s.azi) for s in surveys]

    def run() -> Floats:
        return np.concatenate([MinCurve(md, i, a, frame="nev").poss for md, i, a in inputs])

    return run


def welleng_kernel_loop(surveys: Sequence[Survey]) -> Callable[[], Floats]:
    """welleng's lightest path: its vectorised step kernel ([N, E, TVD] steps) plus a cumsum."""
    inputs = [(np.diff(s.md), s.inc, s.azi) for s in surveys]

    def run() -> Floats:
        out = []
        for dmd, i, a in inputs:
            steps = min_curve_step(dmd, i[:-1], a[:-1], i[1:], a[1:])  # type: ignore[no-untyped-call]
            out.append(np.vstack([np.zeros(3), np.cumsum(steps, axis=0)]))
        return np.concatenate(out)

    return run


def best_ms(run: Callable[[], Floats], repeat: int) -> float:
    """Best-of-``repeat`` wall time of one call, each timing looping for >= 0.2 s."""
    timer = timeit.Timer(run)
    number, _ = timer.autorange()
    return min(timer.repeat(repeat=repeat, number=number)) / number * 1e3


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="timing repeats (best is kept)")
    parser.add_argument("--seed", type=int, default=20261121)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    cases = {
        "1 survey x 10,000 stations": [make_survey(rng, 10_000)],
        "1,000 surveys x 100 stations": [make_survey(rng, 100) for _ in range(1_000)],
    }
    print(
        f"numpy {version('numpy')}, wellpathpy {version('wellpathpy')}, "
        f"welleng {version('welleng')}; best of {args.repeat}"
    )
    print(
        f"{'case':<30}{'ours':>8}{'wpp':>9}{'weng':>9}{'weng-k':>9}{'ratio':>7}"
        f"{'|d| wpp':>11}{'|d| weng':>11}{'|d| weng-k':>11}"
    )
    worst = 0.0
    for name, surveys in cases.items():
        mine = ours(surveys)
        peers = [wellpathpy_loop(surveys), welleng_loop(surveys), welleng_kernel_loop(surveys)]
        reference = mine()
        diffs = [float(np.abs(peer() - reference).max()) for peer in peers]
        worst = max(worst, *diffs)
        t_ours = best_ms(mine, args.repeat)
        t_peers = [best_ms(peer, args.repeat) for peer in peers]
        print(
            f"{name:<30}{t_ours:>8.2f}"
            + "".join(f"{t:>9.2f}" for t in t_peers)
            + f"{min(t_peers) / t_ours:>7.1f}"
            + "".join(f"{d:>11.1e}" for d in diffs)
        )
    print(
        "times in ms per case (best of the repeats); ratio = fastest peer / ours; |d| = largest\n"
        "station-position difference to ours in m. wpp = wellpathpy.mincurve.minimum_curvature,\n"
        "weng = welleng.utils.MinCurve, weng-k = welleng.utils.min_curve_step + cumsum;\n"
        "peers are called once per survey, ours once per case."
    )
    if worst > TOLERANCE_M:
        print(f"FAIL: a peer disagrees by {worst:.3e} m > {TOLERANCE_M:g} m", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
