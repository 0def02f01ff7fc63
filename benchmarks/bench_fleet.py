"""Fleet throughput of gyropipe batch: wells/s, speed-up, the driver's CPU per well, a curve.

``gyropipe batch pipelines/point-gyro.yaml`` (report included, as shipped) over N wells with
1…W workers: wall time, wells/s, speed-up against 1 worker, the batch process's (the
driver's) own CPU per well, the workers' CPU per well, the load before and after, and the
speed-up a many-core machine would see, predicted from the two CPU figures.

The wells are hard links of a few simulated ones (``gyropipe simulate
examples/plans/j-well.yaml --seed K``: 842,201 samples, a 37 MB ``samples.parquet`` each,
47 MB from the simulator the issue measured; simulated once and kept under ``--data``),
named W001…, listed in a manifest. Each batch runs
into a fresh output directory, removed afterwards unless ``--keep``.

How the driver's CPU is measured. The batch runs in this process: the ``gyropipe batch``
command itself (its click command called in-process, ``--quiet``, log lines to a file), so
the driver does exactly what the CLI does, including its process-wide allocator settings,
which ``gp.run_batch`` alone would not make. The local executor forks its workers, which are
separate processes, so ``getrusage(RUSAGE_SELF)`` (user + sys, all threads of this process,
the pool's manager thread included) taken around the command is the driver's CPU and the
workers' is not in it; ``getrusage(RUSAGE_CHILDREN)`` taken around it is the workers' CPU
(the pool is shut down and its processes reaped before the command returns; nothing else is
started meanwhile). A subprocess and its ``/proc/<pid>/stat`` would count the interpreter's
start-up, imports and plugin loading (1.7 s CPU on the 2-core VM: 27 ms a well at 64 wells)
as the driver's; here a one-well batch first warms this process and is not counted, and the
simulated files are read once beforehand (page cache). Columns, per well:

- driver ``CPU``: the whole command (plan, manifest, forking the pool, the loop, summary
  files), the figure the targets are stated in;
- driver ``loop``: its CPU from the executor's start to its close;
- driver ``serial``: the batch thread's busy time in that span — wall time not spent waiting
  for a worker (``Executor.wait``) nor for a core (``/proc/thread-self/schedstat``): its CPU
  plus its blocking waits (ledger fsyncs, the GIL held by the pool's thread), which an idle
  many-core machine still pays;
- worker ``CPU`` (``RUSAGE_CHILDREN``) and ``wall`` (each well's time in its worker, from
  ``summary.json``).

``loop`` and ``serial`` come from wrapping the executor the batch opens
(``pipeline.batch.run.open_executor``, the CLI's code otherwise untouched); should that name
move, they show ``n/a``.

The curve. With d the driver's CPU per well (all in) and w the workers' CPU per well, both
from the run with the most workers, a driver that handles wells one after the other and n
workers in parallel give

    throughput(n) = min(n / w, 1 / d)  wells/s,   speed-up(n) = throughput(n) / throughput(1)

assuming n free cores for the workers and one more for the driver; w the same at every n
(no memory-bandwidth or cache contention, input reads and output writes that keep up: the
hard links are read from the page cache here, a fleet's distinct inputs come from a disk or a
network, and the driver reads each input in full while it hashes it); the driver's per-well
work not growing with n; and N ≫ n (the last round's tail is ignored). The ``by serial``
column puts max(d, serial) in place of d: the driver's blocking waits are not CPU. Where the
machine has at least n cores and n was run, the measured speed-up (1-worker wall / n-worker
wall) is shown beside the prediction; on a shared machine it says more of the load than of
the batch.

    python benchmarks/bench_fleet.py [--wells 64] [--workers-list 1,2] [--quick] [--data DIR]

``--only-changed``: the driver's CPU per well when nothing changed. A first full batch of
the N wells (``--workers``, default 2), then ``--passes`` (default 3) ``gyropipe batch …
--only-changed`` runs over the same, unchanged wells into the same output directory, each
well skipped: the first pass after the files settled
(:data:`pipeline.batch.filestate.SETTLED_S`) has each well's published files looked at by a
worker once, the later ones know every well unchanged from the stat alone. Printed per pass:
the driver's CPU per well (measured as above), its least and median over the stat-only
passes, and the target: ≤ 5 ms a well with 2 workers on 2 cores over ≥ 64 wells (of 47 MB
in the issue; the driver reads no input, so their size does not enter).

    python benchmarks/bench_fleet.py --only-changed [--wells 64] [--workers 2] [--passes 3]

``--reprocess``: what scheduled reprocessing costs the workers. A full batch, then
``--passes`` batches with ``--only-changed --set trajectory.vs_azimuth=…`` (another value
each pass), so that every well runs again on unchanged inputs, whose SHA-256 the workers take
from the ledger (the file's stat key the same) instead of reading them again. Printed: the
workers' CPU a well of the full batch and of each reprocessing pass.

    python benchmarks/bench_fleet.py --reprocess [--wells 64] [--workers 2] [--passes 3]
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "examples" / "plans" / "j-well.yaml"
PIPELINE = ROOT / "pipelines" / "point-gyro.yaml"
PREDICT_AT = (4, 8, 16, 32, 64)
TARGET_WORKERS, TARGET_SPEED_UP = 16, 12.0
TARGET_DRIVER_MS, TARGET_WELLS = 5.0, 64
OPENER = "open_executor"
"""the name under which ``pipeline.batch.run`` opens the batch's executor"""


def cpu_s(who: int) -> float:
    """User + system CPU seconds of ``resource.RUSAGE_SELF`` or ``RUSAGE_CHILDREN``."""
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def gyropipe() -> str:
    """The ``gyropipe`` console script beside this interpreter (its venv's), else the first on
    ``PATH`` (where gyropipe runs from its sources: ``benchmarks/device_many_core.sh``)."""
    beside = Path(sys.executable).parent / "gyropipe"
    found = str(beside) if beside.is_file() else shutil.which("gyropipe")
    if found is None:
        raise SystemExit(f"no gyropipe console script beside {sys.executable} nor on PATH")
    return found


def simulated_from_plan(folder: Path) -> bool:
    """Whether ``folder`` holds a simulation of :data:`PLAN` as it is now."""
    try:
        record = json.loads((folder / "simulation.json").read_text())
        plan = hashlib.sha256(PLAN.read_bytes()).hexdigest()
        return (folder / "samples.parquet").is_file() and record["plan"]["sha256"] == plan
    except (OSError, ValueError, KeyError, TypeError):
        return False


def simulate(data: Path, seeds: int) -> list[Path]:
    """``samples.parquet`` of seeds 1…``seeds``, simulated into ``data/seed-K`` unless there
    from the same plan (written to a temporary directory, then renamed: a killed run leaves no
    half-written well)."""
    sources = []
    for seed in range(1, seeds + 1):
        target = data / f"seed-{seed}"
        if not simulated_from_plan(target):
            print(f"simulating seed {seed} …", flush=True)
            tmp = Path(tempfile.mkdtemp(prefix=f".seed-{seed}-", dir=data))
            cmd = [gyropipe(), "simulate", str(PLAN), "--seed", str(seed), "--out", str(tmp)]
            subprocess.run(cmd, check=True, capture_output=True)
            for unused in ("truth.parquet", "stations.parquet"):
                (tmp / unused).unlink(missing_ok=True)
            shutil.rmtree(target, ignore_errors=True)
            tmp.rename(target)
        sources.append(target / "samples.parquet")
    return sources


def make_wells(data: Path, sources: list[Path], wells: int) -> Path:
    """Wells W001… as hard links of ``sources`` in turn (a symbolic link where the file
    system has none), and a manifest listing them; returns the manifest."""
    folder = data / "wells"
    folder.mkdir(exist_ok=True)
    lines = ["well_id,samples"]
    for i in range(wells):
        name, source = f"W{i + 1:03d}", sources[i % len(sources)]
        link = folder / f"{name}.parquet"
        if not (link.exists() and link.samefile(source)):
            link.unlink(missing_ok=True)
            try:
                link.hardlink_to(source)
            except OSError:
                link.symlink_to(source)
        lines.append(f"{name},wells/{link.name}")
    manifest = data / f"manifest-{wells}-{len(sources)}.csv"
    manifest.write_text("\n".join(lines) + "\n")
    return manifest


def queued_s() -> float:
    """Seconds the calling thread has waited for a core so far (``/proc/thread-self/schedstat``,
    its second field); 0 where the kernel does not say."""
    try:
        return int(Path("/proc/thread-self/schedstat").read_text().split()[1]) / 1e9
    except (OSError, IndexError, ValueError):
        return 0.0


@dataclass
class Probe:
    """The driver from its executor's start to its close: this process's CPU (s), the wall
    time, and of the batch's thread (the main one) the time waiting for workers and, outside
    those waits, for a core."""

    cpu_s: float | None = None
    wall_s: float = 0.0
    waiting_s: float = 0.0
    queued_s: float = 0.0

    @property
    def serial_s(self) -> float:
        """The batch thread's busy time: its CPU and its blocking waits (fsync, the GIL)."""
        return self.wall_s - self.waiting_s - self.queued_s


class TimedExecutor:
    """The batch's executor, unchanged, noting a :class:`Probe` around it."""

    def __init__(self, inner: Any, probe: Probe) -> None:
        self._inner, self._probe = inner, probe
        self._cpu, self._wall, self._queued = (
            cpu_s(resource.RUSAGE_SELF),
            time.perf_counter(),
            queued_s(),
        )
        self._queued_waiting = 0.0

    def submit(self, task: Any) -> None:
        self._inner.submit(task)

    def wait(self, timeout: float) -> Any:
        t0, q0 = time.perf_counter(), queued_s()
        try:
            return self._inner.wait(timeout)
        finally:
            self._probe.waiting_s += time.perf_counter() - t0
            self._queued_waiting += queued_s() - q0

    def close(self, cancel: bool) -> None:
        probe = self._probe
        probe.cpu_s = cpu_s(resource.RUSAGE_SELF) - self._cpu
        probe.wall_s = time.perf_counter() - self._wall
        probe.queued_s = queued_s() - self._queued - self._queued_waiting
        self._inner.close(cancel)


@contextlib.contextmanager
def probed() -> Iterator[Probe]:
    """Wrap the executors the batch opens in :class:`TimedExecutor` (a no-op probe if the
    batch module no longer opens them through ``open_executor``)."""
    from pipeline.batch import run as batch_run

    probe = Probe()
    original = getattr(batch_run, OPENER, None)
    if original is None:
        yield probe
        return

    def opened(*args: Any, **kwargs: Any) -> TimedExecutor:
        return TimedExecutor(original(*args, **kwargs), probe)

    setattr(batch_run, OPENER, opened)
    try:
        yield probe
    finally:
        setattr(batch_run, OPENER, original)


@dataclass
class Run:
    """One batch: ``workers``, ``wells``; seconds; loads (1-minute average) before/after."""

    workers: int
    wells: int
    wall_s: float
    driver_cpu_s: float
    worker_cpu_s: float
    worker_wall_s: float
    """sum over the wells of the run's wall time in its worker (summary.json)"""
    load: tuple[float, float]
    loop_cpu_s: float | None = None
    serial_s: float | None = None

    def per_well_ms(self, seconds: float | None) -> str:
        return "n/a" if seconds is None else f"{seconds / self.wells * 1e3:.1f}"


def batch(
    manifest: Path,
    out: Path,
    workers: int,
    log: Path,
    flags: Sequence[str] = (),
    expect: tuple[str, ...] = ("done", "rejected"),
) -> Run:
    """``gyropipe batch`` (with ``flags``) in this process (module docstring); every well
    must end with a status in ``expect`` (processed; ``skipped`` for ``--only-changed``)."""
    from pipeline.cli import main as cli

    args = ["batch", str(PIPELINE), "--manifest", str(manifest), "--out", str(out)]
    args += ["--workers", str(workers), "--quiet", *flags]
    load0 = os.getloadavg()[0]
    with (
        log.open("a") as sink,
        contextlib.redirect_stdout(sink),
        contextlib.redirect_stderr(sink),
        probed() as probe,
    ):
        self0, children0, wall0 = (
            cpu_s(resource.RUSAGE_SELF),
            cpu_s(resource.RUSAGE_CHILDREN),
            time.perf_counter(),
        )
        try:
            cli.main(args, prog_name="gyropipe", standalone_mode=False)
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        wall = time.perf_counter() - wall0
        driver = cpu_s(resource.RUSAGE_SELF) - self0
        workers_cpu = cpu_s(resource.RUSAGE_CHILDREN) - children0
    written = out / "summary.json"
    wells = json.loads(written.read_text())["wells"] if written.is_file() else []
    processed = [w for w in wells if w["status"] in expect]
    bad = [w for w in wells if w not in processed]
    if bad or not processed or code not in (0, 3):
        first = f": {bad[0]['well']} {bad[0]['status']}: {bad[0]['detail']}" if bad else ""
        raise SystemExit(f"gyropipe batch exited {code}{first} (its log: {log})")
    run = Run(
        workers,
        len(processed),
        wall,
        driver,
        workers_cpu,
        sum(w.get("time_s") or 0.0 for w in processed),
        (load0, os.getloadavg()[0]),
    )
    if probe.cpu_s is not None:
        run.loop_cpu_s, run.serial_s = probe.cpu_s, probe.serial_s
    return run


def speed_up(n: int, d: float, w: float) -> float:
    """The model's speed-up at ``n`` workers (module docstring): driver ``d``, worker ``w``
    seconds per well."""
    return min(n / w, 1 / d) / min(1 / w, 1 / d)


HEADER = (
    f"{'workers':>7} {'wall s':>7} {'wells/s':>7} {'speed-up':>8} │ driver ms/well: "
    f"{'CPU':>5} {'loop':>5} {'serial':>6} │ worker ms/well: {'CPU':>5} {'wall':>5} │ load"
)


def row(r: Run, one: Run | None, label: str | None = None) -> str:
    """A run's line under :data:`HEADER` (first column ``label``, else its workers); the
    speed-up is against the 1-worker run ``one``."""
    gain = f"{one.wall_s / r.wall_s:.2f}×" if one is not None else "—"
    return (
        f"{label or r.workers:>7} {r.wall_s:>7.1f} {r.wells / r.wall_s:>7.2f} {gain:>8} │ "
        f"{'':15} {r.per_well_ms(r.driver_cpu_s):>5} {r.per_well_ms(r.loop_cpu_s):>5} "
        f"{r.per_well_ms(r.serial_s):>5} │ {'':15} {r.per_well_ms(r.worker_cpu_s):>5} "
        f"{r.per_well_ms(r.worker_wall_s):>5} │ {r.load[0]:.1f} → {r.load[1]:.1f}"
    )


def curve(runs: list[Run], cores: int) -> str:
    """The predicted speed-ups (module docstring) from the run with the most workers, with
    the measured ones where this machine has the cores."""
    base = max(runs, key=lambda r: r.workers)
    d, w = base.driver_cpu_s / base.wells, base.worker_cpu_s / base.wells
    serial = None if base.serial_s is None else base.serial_s / base.wells
    one = next((r for r in runs if r.workers == 1), None)
    lines = [
        f"curve from the {base.workers}-worker run: d = {d * 1e3:.1f} ms driver CPU a well, "
        f"w = {w * 1e3:.0f} ms worker CPU a well"
        + ("" if serial is None else f", serial {serial * 1e3:.1f} ms")
        + " → driver-bound from "
        f"n = {w / d:.1f} workers, at most {1 / d:.0f} wells/s",
        f"{'workers':>7} {'predicted':>9} {'by serial':>9} {'measured':>8}",
    ]
    measured = {r.workers: r for r in runs}
    for n in sorted({*measured, *PREDICT_AT}):
        seen = measured.get(n)
        shown = f"{one.wall_s / seen.wall_s:.2f}×" if one and seen and n <= cores else "—"
        by_serial = "n/a" if serial is None else f"{speed_up(n, max(serial, d), w):.1f}×"
        lines.append(f"{n:>7} {speed_up(n, d, w):>8.1f}× {by_serial:>9} {shown:>8}")
    at = speed_up(TARGET_WORKERS, d, w)
    lines.append(
        f"predicts ≥ {TARGET_SPEED_UP:.0f}× at {TARGET_WORKERS} workers: "
        f"{'yes' if at >= TARGET_SPEED_UP else 'no'} ({at:.1f}×)"
    )
    return "\n".join(lines)


def verdict(runs: list[Run]) -> str:
    """The driver target: ≤ 5 ms CPU a well, with 2 workers, over ≥ 64 wells."""
    two = next((r for r in runs if r.workers == 2), None)
    if two is None or two.wells < TARGET_WELLS:
        return f"driver target not measured (needs --workers-list with 2, ≥ {TARGET_WELLS} wells)"
    ms = two.driver_cpu_s / two.wells * 1e3
    return (
        f"driver CPU ≤ {TARGET_DRIVER_MS:.0f} ms a well with 2 workers over {two.wells} wells: "
        f"{'yes' if ms <= TARGET_DRIVER_MS else 'no'} ({ms:.1f} ms)"
    )


def after_full(
    manifest: Path,
    out: Path,
    workers: int,
    passes: int,
    log: Path,
    flags: Callable[[int], list[str]],
    expect: tuple[str, ...] = ("done", "rejected"),
) -> tuple[Run, list[Run]]:
    """A full batch, then ``passes`` batches with ``flags(k)`` (k = 1…) into the same
    ``out``, each after the files settled (their keys and hashes can be remembered) and
    printed; returns the full batch and the passes."""
    from pipeline.batch.filestate import SETTLED_S

    full = batch(manifest, out, workers, log)
    print(HEADER.replace("workers", "   pass", 1), flush=True)
    print(row(full, None, "full"), flush=True)
    runs = []
    for k in range(1, passes + 1):
        time.sleep(SETTLED_S + 0.5)
        runs.append(batch(manifest, out, workers, log, flags(k), expect))
        print(row(runs[-1], None, str(k)), flush=True)
    return full, runs


def only_changed(
    manifest: Path, out: Path, workers: int, passes: int, log: Path, wells: int
) -> list[Run]:
    """A full batch, then ``passes`` ``--only-changed`` batches of the unchanged wells into
    the same ``out`` (module docstring), each printed; returns the ``--only-changed`` runs."""
    _, runs = after_full(
        manifest, out, workers, passes, log, lambda k: ["--only-changed"], ("skipped",)
    )
    if any(r.wells != wells for r in runs):
        raise SystemExit(f"not every well was skipped as unchanged (its log: {log})")
    stat_only = [r.driver_cpu_s / r.wells * 1e3 for r in runs[1:]] or [
        runs[0].driver_cpu_s / runs[0].wells * 1e3
    ]
    least, median = min(stat_only), statistics.median(stat_only)
    which = "passes 2…" if len(runs) > 1 else "pass 1"
    print(
        f"\n--only-changed, {workers} workers, {wells} unchanged wells: driver CPU a well "
        f"(pass 1, publications looked at by workers: "
        f"{runs[0].driver_cpu_s / runs[0].wells * 1e3:.2f} ms); {which}: least "
        f"{least:.2f} ms, median {median:.2f} ms"
    )
    measured = workers == 2 and wells >= TARGET_WELLS
    print(
        f"driver CPU ≤ {TARGET_DRIVER_MS:.0f} ms a well, --only-changed, 2 workers over "
        f"≥ {TARGET_WELLS} wells: "
        + (
            f"{'yes' if median <= TARGET_DRIVER_MS else 'no'} (median {median:.2f} ms)"
            if measured
            else f"not measured (needs --workers 2 and --wells ≥ {TARGET_WELLS})"
        )
    )
    return runs


def reprocess(manifest: Path, out: Path, workers: int, passes: int, log: Path) -> list[Run]:
    """A full batch, then ``passes`` batches of the same wells with ``--only-changed`` and a
    changed parameter (``--set trajectory.vs_azimuth=…``, another value each pass: every well
    runs again, its inputs unchanged) into the same ``out``, each printed; returns them. The
    workers of a reprocessing batch take each input's SHA-256 from the ledger (its stat key
    unchanged) instead of reading the file again."""
    full, runs = after_full(
        manifest,
        out,
        workers,
        passes,
        log,
        lambda k: ["--only-changed", "--set", f"trajectory.vs_azimuth={10.0 * k}"],
    )
    per_well = [r.worker_cpu_s / r.wells * 1e3 for r in runs]
    first = full.worker_cpu_s / full.wells * 1e3
    print(
        f"\nworker CPU a well: full batch {first:.1f} ms; reprocessing (inputs not hashed "
        f"again) least {min(per_well):.1f} ms, median {statistics.median(per_well):.1f} ms"
    )
    return runs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data",
        type=Path,
        default=Path(tempfile.gettempdir()) / "gyropipe-bench-fleet",
        help="simulated wells (kept), links, manifests and runs (default: %(default)s)",
    )
    parser.add_argument(
        "--wells", type=int, default=TARGET_WELLS, help="wells a batch (default: %(default)s)"
    )
    parser.add_argument("--seeds", type=int, default=4, help="distinct simulated wells")
    parser.add_argument(
        "--workers-list",
        default="1,2",
        help="comma-separated worker counts (e.g. 1,2,4,8,16 on a bigger machine)",
    )
    parser.add_argument("--quick", action="store_true", help="skip the 1-worker run")
    parser.add_argument("--keep", action="store_true", help="keep the output directories")
    parser.add_argument(
        "--only-changed",
        action="store_true",
        help="a full batch, then --passes --only-changed batches of the unchanged wells",
    )
    parser.add_argument(
        "--reprocess",
        action="store_true",
        help="a full batch, then --passes batches re-running every well with a changed parameter",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=2,
        help="workers of --only-changed and --reprocess (default: 2)",
    )
    parser.add_argument(
        "--passes", type=int, default=3, help="--only-changed batches (default: %(default)s)"
    )
    args = parser.parse_args()
    if (args.only_changed or args.reprocess) and (args.workers < 1 or args.passes < 1):
        parser.error("--workers and --passes must be ≥ 1")
    counts = sorted({int(n) for n in args.workers_list.split(",")})
    if args.quick and len(counts) > 1:
        counts = [n for n in counts if n != 1]
    if args.wells < 1 or args.seeds < 1 or not counts or counts[0] < 1:
        parser.error("--wells, --seeds and the worker counts must be ≥ 1")
    data: Path = args.data.resolve()
    data.mkdir(parents=True, exist_ok=True)
    sources = simulate(data, args.seeds)
    manifest = make_wells(data, sources, args.wells)
    for source in sources:  # the page cache, as for every run after the first
        with source.open("rb") as f:
            while f.read(1 << 24):
                pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cores = cores or 1
    runs_dir = data / "runs"
    runs_dir.mkdir(exist_ok=True)
    log = runs_dir / "batch.log"
    log.write_text("")
    print(
        f"{args.wells} wells (hard links of {len(sources)} simulated, "
        f"{sources[0].stat().st_size / 1e6:.0f} MB each), {PIPELINE.relative_to(ROOT)}, "
        f"{cores} cores, batch log {log}; load " + " ".join(f"{x:.2f}" for x in os.getloadavg())
    )
    warm = Path(tempfile.mkdtemp(prefix="warm-", dir=runs_dir))
    try:  # a one-well warm-up (imports, plugins), not counted
        batch(make_wells(data, sources, 1), warm, 1, log)
    finally:
        shutil.rmtree(warm, ignore_errors=True)
    if args.only_changed or args.reprocess:
        mode = "only-changed" if args.only_changed else "reprocess"
        out = Path(tempfile.mkdtemp(prefix=f"{mode}-w{args.workers}-", dir=runs_dir))
        try:
            if args.only_changed:
                only_changed(manifest, out, args.workers, args.passes, log, args.wells)
            else:
                reprocess(manifest, out, args.workers, args.passes, log)
        finally:
            if not args.keep:
                shutil.rmtree(out, ignore_errors=True)
        return 0
    print(HEADER, flush=True)
    runs: list[Run] = []
    for workers in counts:  # 0: a one-well warm-up (imports, plugins), not counted
        out = Path(tempfile.mkdtemp(prefix=f"w{workers}-", dir=runs_dir))
        try:
            runs.append(batch(manifest, out, workers, log))
            print(row(runs[-1], runs[0] if runs[0].workers == 1 else None), flush=True)
        finally:
            if not args.keep:
                shutil.rmtree(out, ignore_errors=True)
    print(f"\n{curve(runs, cores)}\n{verdict(runs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
