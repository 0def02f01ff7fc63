"""One well end to end: ``gyropipe run`` of the shipped point-gyro and continuous pipelines,
an old commit beside this tree, in one run.

Simulates ``examples/plans/j-well.yaml`` (point survey, 842k samples) and
``j-well-continuous.yaml`` (continuous run, 164k samples) once, extracts the old commit's
``src/`` and ``pipelines/`` (``git archive``, no worktree) and runs each pipeline as a fresh
process, old and new interleaved ``--runs`` times (each its own interpreter: start-up and
imports count, as they do for a user). Prints the machine's load before and after, the
median wall time of each and their ratio (target: new ≥ 3× faster) with the CPU time
(user + system) beside it (less sensitive to a shared machine's load), and where a well's wall
time goes: start-up and imports (process wall minus the runner's) and each stage's share
(the runner records every stage's wall time in ``run.json``).

Both trees are byte-compiled (``compileall``) before anything is timed, as a pip-installed
package is: otherwise, where ``PYTHONDONTWRITEBYTECODE`` is set (as in some containers and
CI images), every run would compile every module from source again — a cost no user pays.

    python benchmarks/bench_well.py [--old main] [--runs 3] [--data DIR]
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES = {  # pipeline → simulation plan
    "point-gyro": "j-well",
    "continuous-gyro": "j-well-continuous",
}
MAIN = "import sys; from pipeline.cli import main; sys.argv[0] = 'gyropipe'; main()"


def load() -> str:
    """The machine's load as ``uptime`` states it."""
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def extract(rev: str, into: Path) -> Path:
    """``src/`` and ``pipelines/`` of commit ``rev`` under ``into``."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", "--format=tar", rev, "src", "pipelines"],
        check=True,
        capture_output=True,
    ).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    return into


def gyropipe(tree: Path, *args: str) -> tuple[float, float]:
    """Wall and CPU time (user + system, the child's) of ``gyropipe ARGS`` run from
    ``tree``'s sources, seconds."""
    env = {**os.environ, "PYTHONPATH": str(tree / "src")}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", MAIN, *args], env=env, capture_output=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"gyropipe {' '.join(args)} ({tree}) failed:\n{done.stderr.decode()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def shares(out: Path, wall: float) -> list[tuple[str, float]]:
    """(part, share of the process wall time): start-up and imports, then each stage."""
    manifest = json.loads((out / "run.json").read_text())
    parts = [("start-up, imports, run.json", (wall - manifest["wall_time_s"]) / wall)]
    parts += [(s["id"], s["wall_time_s"] / wall) for s in manifest["stages"]]
    return parts


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="main", help="commit to compare with (default: main)")
    parser.add_argument("--runs", type=int, default=3, help="interleaved runs of each")
    parser.add_argument(
        "--data", type=Path, default=Path(tempfile.gettempdir()) / "gyropipe-bench-well"
    )
    args = parser.parse_args()
    args.data.mkdir(parents=True, exist_ok=True)
    print(f"{os.cpu_count()} CPUs; at start: {load()}")
    for plan in CASES.values():
        if not (args.data / plan / "samples.parquet").is_file():
            plan_file = str(ROOT / "examples" / "plans" / f"{plan}.yaml")
            gyropipe(ROOT, "simulate", plan_file, "--out", str(args.data / plan))
    with tempfile.TemporaryDirectory() as tmp:
        old = extract(args.old, Path(tmp) / "old")
        trees = {"old": old, "new": ROOT}
        for tree in trees.values():  # as installed: byte-compiled once, not on every run
            if not compileall.compile_dir(tree / "src", quiet=1):
                raise SystemExit(f"{tree / 'src'}: some module does not compile")
        results: dict[tuple[str, str], list[float]] = {}
        cpus: dict[tuple[str, str], list[float]] = {}
        last: dict[tuple[str, str], list[tuple[str, float]]] = {}
        for _ in range(args.runs):
            for pipeline, plan in CASES.items():
                for label, tree in trees.items():
                    out = Path(tmp) / f"{label}-{pipeline}"
                    wall, cpu = gyropipe(
                        tree,
                        "run",
                        str(tree / "pipelines" / f"{pipeline}.yaml"),
                        "--input",
                        str(args.data / plan / "samples.parquet"),
                        "--out",
                        str(out),
                    )
                    results.setdefault((label, pipeline), []).append(wall)
                    cpus.setdefault((label, pipeline), []).append(cpu)
                    last[(label, pipeline)] = shares(out, wall)
    print(f"at end: {load()}\n")
    print(f"old = {args.old}, new = this tree; median of {args.runs} interleaved runs")
    for pipeline in CASES:
        t_old = statistics.median(results[("old", pipeline)])
        t_new = statistics.median(results[("new", pipeline)])
        c_old = statistics.median(cpus[("old", pipeline)])
        c_new = statistics.median(cpus[("new", pipeline)])
        print(
            f"{pipeline:16} wall: old {t_old:6.2f} s  new {t_new:6.2f} s  → {t_old / t_new:.2f}× "
            f"(target ≥ 3×);  CPU: old {c_old:6.2f} s  new {c_new:6.2f} s  → {c_old / c_new:.2f}×"
        )
    for pipeline in CASES:
        print(f"\n{pipeline}: share of a well's wall time (last run)")
        print(f"  {'part':28} {'old':>6} {'new':>6}")
        old_parts = dict(last[("old", pipeline)])
        for part, share in last[("new", pipeline)]:
            before = old_parts.get(part)
            shown = f"{before:6.1%}" if before is not None else f"{'-':>6}"
            print(f"  {part:28} {shown} {share:6.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
