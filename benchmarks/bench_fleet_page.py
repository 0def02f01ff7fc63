"""The fleet page of N wells (default 1000): CPU time to build it and its size.

One clearance well (``pipelines/clearance.yaml`` on ``examples/clearance``: trajectory,
clearance table of 6 offset wells × 100 stations, report) is run once by a 1-well batch;
its published directory is hard-linked N times (``OUT/W-0000`` …) and the page of the N
wells built with every well's figures read from its published outputs, as ``gyropipe status
DIR --html`` builds it (a batch has its workers read those of the wells it ran). Printed:
CPU ms per well (user + sys of this process, ``resource.getrusage``) for the whole page and
for its floor — reading each well's ``run.json`` alone — the page's bytes per well, and the
load average.

    python benchmarks/bench_fleet_page.py [--wells 1000]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
from pathlib import Path

import pipeline as gp
from pipeline.batch.fleet_page import Fleet, FleetWell, fleet_html
from pipeline.manifest import MANIFEST

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "clearance"


def cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def one_well(work: Path) -> Path:
    """A batch of one clearance well; its published directory."""
    manifest = work / "wells.csv"
    manifest.write_text(
        f"well_id,reference,offsets\nW,{EXAMPLES / 'reference.csv'},{EXAMPLES / 'manifest.csv'}\n"
    )
    report = gp.run_batch(
        ROOT / "pipelines" / "clearance.yaml",
        manifest=manifest,
        out=work / "one",
        workers=1,
        set={
            "clearance.reference_model": "ISCWSA-MWD-REV4",
            "clearance.reference_hole_diameter": 0.9144,
        },
        log=open(os.devnull, "w"),  # noqa: SIM115 - the batch's log, dropped
    )
    assert report.exit_code == 0, report.results
    return work / "one" / "W"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--wells", type=int, default=1000)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        source = one_well(work)
        out = work / "out"
        wells = []
        for k in range(args.wells):
            well_dir = out / f"W-{k:04d}"
            shutil.copytree(source, well_dir, copy_function=os.link)
            wells.append(FleetWell(well_dir.name, "done", "new well", 0.5, None, well_dir))
        fleet = Fleet("Batch 1", (), tuple(wells))
        t0 = cpu()
        for well in wells:
            (well.well_dir / MANIFEST).read_bytes()
        floor = cpu() - t0
        t0 = cpu()
        page = fleet_html(fleet, out)
        spent = cpu() - t0
    n = args.wells
    print(
        f"{n} wells: page {spent / n * 1e3:.2f} ms CPU per well ({spent:.2f} s), "
        f"floor (read run.json) {floor / n * 1e3:.3f} ms per well; "
        f"{len(page.encode()) / n:.0f} bytes per well ({len(page.encode()) / 1e6:.2f} MB)"
    )
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
