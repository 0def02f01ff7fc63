"""Benchmark the anti-collision scan against welleng's ISCWSA clearance, in the same run.

Run from the repository root: ``python benchmarks/bench_clearance.py [--offsets N]
[--stations N] [--rounds N]``. One reference well of 1,000 stations against 100 offset wells
of 1,000 stations each (default), drilled from a pad of slots 4–60 m from the reference,
each kicking off at its own depth and building to its own inclination and azimuth. Every
well is surveyed with the ISCWSA MWD Rev 4 model (50,000 nT, dip 70°, declination 0, 60° N).

Timed, interleaved (``timing.interleaved``), from stations to separation factors:

- gyropipe: ``gp.clearance`` (each well's covariance, closest points, SF and levels);
- welleng: ``Survey(..., error_model="ISCWSA MWD Rev4")`` per well and
  ``IscwsaClearance(reference, offset, minimize_sf=False)`` per offset well.

Prints median wall and CPU times, the ratio, the largest relative SF difference between the
two (each with its own Rev 4 implementation) and ``uptime`` before and after.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from typing import Any

import numpy as np
import pandas as pd
import welleng as we

import pipeline as gp
from timing import interleaved, uptime

FIELD = {"total_field": 50000.0, "dip": 70.0, "declination": 0.0}
SITE = {"latitude": 60.0, "longitude": 2.0, "north_reference": "true", "declination": 0.0}
HOLE = 12.25 * 0.0254  # m


def well(n: int, rng: np.random.Generator, depth: float = 3000.0) -> pd.DataFrame:
    """n stations to ``depth`` m MD: vertical to a kick-off, build, then hold."""
    md = np.linspace(0.0, depth, n)
    kickoff = rng.uniform(200.0, 1200.0)
    target = rng.uniform(10.0, 70.0)
    build = rng.uniform(1.5, 3.0) / 30.0  # deg/m
    inc = np.clip((md - kickoff) * build, 0.0, target)
    azi = np.full(n, rng.uniform(0.0, 360.0))
    frame = pd.DataFrame({"md": md, "inc": inc, "azi": azi})
    frame.attrs["north_reference"] = "true"
    return frame


def pad(n_offsets: int, n: int) -> tuple[pd.DataFrame, dict[str, pd.DataFrame], dict[str, Any]]:
    rng = np.random.default_rng(2026)
    reference = well(n, rng)
    offsets = {f"W{k:03d}": well(n, rng) for k in range(n_offsets)}
    radius = rng.uniform(4.0, 60.0, n_offsets)
    angle = rng.uniform(0.0, 2 * np.pi, n_offsets)
    slots = {
        name: (float(r * np.cos(a)), float(r * np.sin(a)))
        for name, r, a in zip(offsets, radius, angle, strict=True)
    }
    return reference, offsets, slots


def ours(reference: pd.DataFrame, offsets: dict[str, pd.DataFrame], slots: dict[str, Any]):  # type: ignore[no-untyped-def]
    return gp.clearance(
        reference,
        offsets,
        offset_model="ISCWSA-MWD-REV4",
        offset_hole_diameter=HOLE,
        offset_position=slots,
        reference_model="ISCWSA-MWD-REV4",
        reference_hole_diameter=HOLE,
        magnetic=FIELD,
        well=SITE,
    )


def survey(frame: pd.DataFrame, start: tuple[float, float] = (0.0, 0.0)):  # type: ignore[no-untyped-def]
    header = we.survey.SurveyHeader(
        latitude=SITE["latitude"],
        longitude=SITE["longitude"],
        b_total=FIELD["total_field"],
        dip=FIELD["dip"],
        declination=FIELD["declination"],
        azi_reference="true",
    )
    return we.survey.Survey(
        md=frame.md.to_numpy(),
        inc=frame.inc.to_numpy(),
        azi=frame.azi.to_numpy(),
        header=header,
        start_nev=[start[0], start[1], 0.0],
        radius=np.full(len(frame), HOLE / 2),
        error_model="ISCWSA MWD Rev4",
    )


def welleng(reference: pd.DataFrame, offsets: dict[str, pd.DataFrame], slots: dict[str, Any]):  # type: ignore[no-untyped-def]
    ref = survey(reference)
    return {
        name: np.ravel(
            we.clearance.IscwsaClearance(ref, survey(frame, slots[name]), minimize_sf=False).sf
        )
        for name, frame in offsets.items()
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--offsets", type=int, default=100)
    parser.add_argument("--stations", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    reference, offsets, slots = pad(args.offsets, args.stations)
    print(f"before: {uptime()}")
    print(
        f"1 reference well x {args.offsets} offset wells, {args.stations} stations each, "
        f"ISCWSA MWD Rev 4, {args.rounds} interleaved rounds"
    )
    timings = interleaved(
        {
            "gyropipe": lambda: ours(reference, offsets, slots),
            "welleng": lambda: welleng(reference, offsets, slots),
        },
        args.rounds,
    )
    print(f"after:  {uptime()}")
    for name, t in timings.items():
        print(f"{name:>9}: wall {t.median:8.2f} s   cpu {t.cpu_median:8.2f} s")
    print(
        f"welleng / gyropipe (wall): {timings['welleng'].median / timings['gyropipe'].median:.1f}x"
    )
    table = timings["gyropipe"].result
    theirs = timings["welleng"].result
    worst = 0.0
    for name, sf in theirs.items():
        mine = table[table.offset == name].sf.to_numpy()
        close = np.abs(sf) < 1e3  # far wells: both are large and rounding dominates nothing
        worst = max(worst, float(np.abs(mine[close] / sf[close] - 1.0).max()))
    print(f"largest relative SF difference (SF < 1000): {worst:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
