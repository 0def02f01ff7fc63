"""One well's CPU in two source trees, well for well: a before/after comparison that a shared
machine's changing load tilts far less than two runs one after the other.

Two warm worker processes, one per tree (``PYTHONPATH`` = its ``src``), each set up as
:mod:`bench_well_floor` sets up its worker and warmed up by one well, run a well in turn —
this tree's, the other's, the other's, this tree's, … — each its floor first
(:data:`bench_well_floor.FLOORS`, in its own process). A slow spell falls on both alike, so
the median of the pairs' differences shows a change that the spread of either tree's wells
would hide. Prints the load, each tree's least and median of the floor, the worker, the
readings, continuous, MCAP export and report stages (CPU ms; 0 for a pipeline without one),
the medians of the differences, and each tree's ratio to the floor (the least and the median
of both trees' floors: the same code).

    python benchmarks/bench_well_pair.py OTHER_TREE [--pipeline point-gyro] [--pairs 30]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve()
STAGES = ("readings", "continuous", "export_mcap", "report")
COLUMNS = ("floor", "worker", *STAGES)


def child(name: str, data: Path) -> None:
    """The worker of one tree: runs well ``n`` for each line ``n`` on stdin and prints its
    floor's, the whole well's and :data:`STAGES`' CPU ms."""
    sys.path.insert(0, str(HERE.parent))
    import bench_well_floor as b

    root = Path(os.environ["PYTHONPATH"]).parent
    samples = data / b.CASES[name] / "samples.parquet"
    b.worker_setup()
    clock = b.Clock()
    spec = b.load_spec(root / "pipelines" / f"{name}.yaml").spec
    assert spec is not None
    ref = b.PipelineRef(str(root / "pipelines" / f"{name}.yaml"), spec)
    floor = b.FLOORS[name]
    with tempfile.TemporaryDirectory() as out:
        floor(samples)
        b.checked(b.run_well(b.task(ref, samples, Path(out), 0), ref))  # warm-up
        print("ready", flush=True)
        for line in sys.stdin:
            spent = b.timed(lambda: floor(samples))
            clock.spent.clear()
            start = b.cpu()
            b.checked(b.run_well(b.task(ref, samples, Path(out), int(line)), ref))
            cpus = [spent, b.cpu() - start, *(clock.spent.get(s, 0.0) for s in STAGES)]
            print(" ".join(f"{c * 1e3:.3f}" for c in cpus), flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("other", type=Path, help="the other source tree (its repository root)")
    parser.add_argument(
        "--pipeline", default="point-gyro", choices=["point-gyro", "continuous-gyro"]
    )
    parser.add_argument("--pairs", type=int, default=30)
    parser.add_argument(
        "--data", type=Path, default=Path(tempfile.gettempdir()) / "gyropipe-bench-floor"
    )
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.pipeline, args.data)
        return 0
    sys.path.insert(0, str(HERE.parent))
    import bench_well_floor as b

    if not (args.data / b.CASES[args.pipeline] / "samples.parquet").is_file():
        raise SystemExit(f"no simulated well in {args.data}: run bench_well_floor.py --data first")
    trees = {"this": HERE.parents[1], "other": args.other.resolve()}
    command = [sys.executable, str(HERE), str(args.other), "--child"]
    command += ["--pipeline", args.pipeline, "--data", str(args.data)]
    workers = {}
    for label, tree in trees.items():
        env = {**os.environ, "PYTHONPATH": str(tree / "src")}
        workers[label] = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env
        )
    for worker in workers.values():
        assert worker.stdin is not None and worker.stdout is not None
        if worker.stdout.readline().strip() != "ready":
            raise SystemExit("a worker failed to start")
    print(f"at start: {b.load()}")
    got: dict[str, list[list[float]]] = {label: [] for label in trees}
    for n in range(1, args.pairs + 1):
        for label in ("this", "other") if n % 2 else ("other", "this"):
            worker = workers[label]
            assert worker.stdin is not None and worker.stdout is not None
            worker.stdin.write(f"{n}\n")
            worker.stdin.flush()
            got[label].append([float(v) for v in worker.stdout.readline().split()])
    print(f"at end:   {b.load()}\n")
    for worker in workers.values():
        assert worker.stdin is not None
        worker.stdin.close()
        worker.wait()
    print(f"{args.pipeline}, {args.pairs} pairs, CPU ms: least (median) of each tree; this − other")
    for k, column in enumerate(COLUMNS):
        this, other = ([row[k] for row in got[label]] for label in ("this", "other"))
        change = statistics.median(t - o for t, o in zip(this, other, strict=True))
        print(
            f"  {column:11} this {min(this):6.1f} ({statistics.median(this):6.1f})   other "
            f"{min(other):6.1f} ({statistics.median(other):6.1f})   median change {change:+6.1f}"
        )
    floors = [row[0] for label in trees for row in got[label]]  # the same code in both
    for label in trees:
        wells = [row[1] for row in got[label]]
        print(
            f"  ratio to the floor (both trees' floors), {label}: {min(wells) / min(floors):.2f}× "
            f"(medians {statistics.median(wells) / statistics.median(floors):.2f}×)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
