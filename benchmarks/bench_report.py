"""Where the report stage's time goes, against the well it reports on.

Runs ``pipelines/point-gyro.yaml`` and ``pipelines/continuous-gyro.yaml`` once on the
simulated wells of ``bench_well.py`` (same data directory), then, in a fresh interpreter,
makes the report again from the tables the run persisted and times each part in CPU seconds
(this process; ``time.process_time``) and wall: importing the report modules, building the
document, laying out every figure (the report's own vector charts), the HTML (inline SVG),
and the PDF (layout, fonts, path operators). A second, warm pass shows what is left once
the imports are paid (a batch worker's case). Prints the load before and after, and the
report's share of the well's own CPU time.

    python benchmarks/bench_report.py [--data DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
CASES = {"point-gyro": "j-well", "continuous-gyro": "j-well-continuous"}

PHASES = r"""
import json, sys, time, datetime
from pathlib import Path
import pyarrow.parquet as pq
from pipeline.registry import Provenance
from pipeline.well import WellMetadata
from pipeline.streams import TableStream

out, wiring = Path(sys.argv[1]), json.loads(sys.argv[2])
tables = {port: pq.read_table(out / f"{source}.parquet") for port, source in wiring.items()}
times = {}

def timed(name, call):
    cpu, wall = time.process_time(), time.perf_counter()
    result = call()
    times[name] = (time.process_time() - cpu, time.perf_counter() - wall)
    return result

def imports():
    import pipeline.reports.survey, pipeline.reports.html, pipeline.reports.figures
    import pipeline.reports.pdf

timed("import report modules", imports)
from pipeline.reports.envelope import full_rate
from pipeline.reports.figures import Figures
from pipeline.reports.html import render_html
from pipeline.reports.pdf import render_pdf
from pipeline.reports.survey import SurveyTables, survey_document

provenance = Provenance("bench", "1", "bench.yaml", "0" * 64, "0", {}, {},
                        datetime.datetime(2026, 1, 1, tzinfo=datetime.UTC), ())
for label in ("cold", "warm"):
    def document():
        given = dict(tables)
        if "series" in given:
            given["series"] = full_rate(TableStream.from_table(given["series"]), "true north")
        return survey_document(SurveyTables(**given), WellMetadata(well="bench"), provenance,
                               "Gyro survey report", ())  # no plugin's report parts
    doc = timed(f"{label}: document (incl. series envelope)", document)
    figures = Figures()
    timed(f"{label}: lay out figures (vector)", lambda: [figures.scene(p) for p in doc.plots()])
    timed(f"{label}: HTML (inline SVG)", lambda: render_html(doc, figures))
    timed(f"{label}: PDF (layout, fonts, paths)",
          lambda: render_pdf(doc, out / f"bench-{label}.pdf", figures))
print(json.dumps(times))
"""


def load() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def run(args: list[str], env: dict[str, str]) -> tuple[str, float, float]:
    """stdout, wall and CPU seconds (the child's user + system) of a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args[:3])} failed:\n{done.stderr}")
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return done.stdout, wall, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, default=Path(tempfile.gettempdir()) / "gyropipe-bench-well"
    )
    args = parser.parse_args()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    cli = ["-c", "import sys; from pipeline.cli import main; sys.argv[0] = 'gyropipe'; main()"]
    print(f"{os.cpu_count()} CPUs; at start: {load()}")
    for pipeline, plan in CASES.items():
        samples = args.data / plan / "samples.parquet"
        if not samples.is_file():
            run([*cli, "simulate", str(ROOT / "examples/plans" / f"{plan}.yaml"), "--out",
                 str(args.data / plan)], env)  # fmt: skip
        spec = yaml.safe_load((ROOT / "pipelines" / f"{pipeline}.yaml").read_text())
        wiring = next(s["inputs"] for s in spec["stages"] if s["id"] == "report")
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out"
            _, wall, cpu = run([*cli, "run", str(ROOT / "pipelines" / f"{pipeline}.yaml"),
                                "--input", str(samples), "--out", str(out)], env)  # fmt: skip
            stages = {
                s["id"]: s["wall_time_s"]
                for s in json.loads((out / "run.json").read_text())["stages"]
            }
            stdout, _, _ = run(["-c", PHASES, str(out), json.dumps(wiring)], env)
        phases = json.loads(stdout.strip().splitlines()[-1])
        cold = sum(c for name, (c, _) in phases.items() if not name.startswith("warm"))
        warm = sum(c for name, (c, _) in phases.items() if name.startswith("warm"))
        share = stages["report"] / wall
        print(f"\n{pipeline}: well {wall:.2f} s wall, {cpu:.2f} s CPU; report stage "
              f"{stages['report']:.2f} s wall ({share:.0%} of the well)")  # fmt: skip
        print(f"  {'part':48} {'CPU s':>7} {'wall s':>7}")
        for name, (c, w) in phases.items():
            print(f"  {name:48} {c:7.3f} {w:7.3f}")
        print(f"  report CPU, cold {cold:.2f} s = {cold / cpu:.0%} of the well's CPU; "
              f"warm (imports paid) {warm:.2f} s = {warm / cpu:.0%}")  # fmt: skip
    print(f"\nat end: {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
