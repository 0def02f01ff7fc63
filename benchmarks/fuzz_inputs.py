"""Long fuzz run of every input kind gyropipe reads (the harness: ``tests/fuzz_support.py``).

Runs ``--count`` mutated inputs of each kind with the given ``--seed`` through the code
paths the CLI uses (in process), prints a table of the outcomes per kind and the first
examples of every outcome that is not ``accepted`` or ``refused``, each saved under
``--out`` for reproduction (the input file, and a ``.txt`` with the mutations, the outcome
and the command that replays it). Exits 1 if any input broke the contract (a traceback, a
hang, non-finite or contract-breaking output, an unreadable copy, a validate reporting one
of two problems, a peak resident memory past 1 GiB) or printed a warning other than
gyropipe's own (NumPy's overflow…). The fault kinds (``tests/fuzz_faults.py``: special files
in a manifest, a corrupted ledger, file-system faults) run as the input kinds do.

    python benchmarks/fuzz_inputs.py --count 10000 --seed 1 --out /tmp/fuzz --jobs 2
    python benchmarks/fuzz_inputs.py --replay csv-stations 4711 --seed 1   # one input again
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from fuzz_support import (  # noqa: E402  (tests/ is put on the path first)
    ACCEPTED,
    BAD,
    KIND_NAMES,
    REFUSED,
    Fuzzer,
    Outcome,
    format_table,
)

WARNED = "warned"
"""Inputs that raised a warning other than InputFileWarning (counted beside the outcomes)."""
BIG = "over-1GiB"
"""Inputs that raised the process's peak resident memory past :data:`OVER` (counted beside
the outcomes, as a contract breach)."""
OVER = 2**30
SHOWN = (ACCEPTED, REFUSED)
"""Outcomes that need no example."""
COST = {"las-samples": 5, "csv-readings": 5, "parquet": 4, "witsml": 4, "csv-samples": 3}
"""Rough relative cost of an input of a kind (the costliest start first)."""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=10_000, help="inputs per kind")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--kinds", default=",".join(KIND_NAMES), help="comma-separated kinds")
    parser.add_argument("--out", type=Path, default=None, help="directory for the examples")
    parser.add_argument("--examples", type=int, default=5, help="examples kept per outcome")
    parser.add_argument(
        "--budget", type=float, default=10.0, help="CPU seconds per input (wall clock: 6×)"
    )
    parser.add_argument("--jobs", type=int, default=1, help="processes (one kind each)")
    parser.add_argument("--memory", type=float, default=8.0, help="GiB of memory per process")
    parser.add_argument("--replay", nargs=2, metavar=("KIND", "INDEX"), help="run one input")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="gyropipe-fuzz-"))
    if args.replay:
        kind, index = args.replay[0], int(args.replay[1])
        outcome = _replay(kind, index, args.seed, out, args.budget)
        print(f"{outcome.label}: {outcome.detail}")
        return 1 if outcome.bad else 0
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    unknown = sorted(set(kinds) - set(KIND_NAMES))
    if unknown:
        parser.error(f"unknown kinds {unknown} (kinds: {', '.join(KIND_NAMES)})")
    kinds.sort(key=lambda k: -COST.get(k, 1))
    tasks = [
        (k, args.seed, args.count, out, args.examples, args.budget, args.memory) for k in kinds
    ]
    started = time.perf_counter()
    print(f"fuzzing {len(kinds)} kinds × {args.count} inputs, seed {args.seed}, examples in {out}")
    if args.jobs > 1:
        with multiprocessing.get_context("spawn").Pool(args.jobs) as pool:
            results = list(pool.imap_unordered(_run_kind, tasks))
    else:
        results = [_run_kind(task) for task in tasks]
    by_kind = {r["kind"]: r for r in results}
    counts = {k: Counter(by_kind[k]["counts"]) for k in KIND_NAMES if k in by_kind}
    print()
    print(format_table(counts))
    print(f"\n{time.perf_counter() - started:.0f} s in all")
    for kind in counts:
        for label, examples in by_kind[kind]["examples"].items():
            print(f"\n{kind} / {label}: {counts[kind][label]} input(s); first:")
            for example in examples:
                print(f"  #{example['index']} {example['mutations']}\n    {example['detail']}")
                print(f"    saved: {example['file']}")
    summary = {
        k: {"counts": dict(c), **{m: by_kind[k][m] for m in ("seconds", "peak_rss_mib")}}
        for k, c in counts.items()
    }
    (out / "summary.json").write_text(json.dumps({"seed": args.seed, "kinds": summary}, indent=2))
    bad = sum(c[label] for c in counts.values() for label in (*BAD, BIG))
    warned = sum(c[WARNED] for c in counts.values())
    print(
        f"\n{'FAIL' if bad or warned else 'ok'}: {bad} input(s) broke the contract, {warned} "
        f"printed a warning other than gyropipe's own; summary {out}"
    )
    return 1 if bad or warned else 0


def _run_kind(task: tuple[str, int, int, Path, int, float, float]) -> dict[str, object]:
    """Fuzz one kind (in a worker process when --jobs > 1)."""
    kind, seed, count, out, keep, budget, memory = task
    _limit_memory(memory)
    fuzzer = Fuzzer(out / "work" / kind, budget=budget)
    counts: Counter[str] = Counter()
    examples: dict[str, list[dict[str, object]]] = {}
    started = time.perf_counter()
    slowest = 0.0
    peak = _peak_rss()
    for outcome in fuzzer.fuzz(kind, seed, count):
        counts[outcome.label] += 1
        slowest = max(slowest, outcome.seconds)
        if (now := _peak_rss()) > peak:  # this input raised the process's peak
            peak = now
            if now > OVER:
                counts[BIG] += 1
                big = examples.setdefault(BIG, [])
                if len(big) < keep:
                    big.append(_save(outcome, out, seed, f"peak RSS {now / 2**20:.0f} MiB", BIG))
        kept = examples.setdefault(outcome.label, []) if outcome.label not in SHOWN else None
        if kept is not None and len(kept) < keep:
            kept.append(_save(outcome, out, seed))
        if outcome.warnings:  # not an outcome of its own: counted and shown beside them
            counts[WARNED] += 1
            warned = examples.setdefault(WARNED, [])
            if len(warned) < keep:
                warned.append(_save(outcome, out, seed, "; ".join(outcome.warnings)))
        done = sum(counts.values())
        if done % 250 == 0:
            print(f"  {kind}: {done}/{count} {dict(counts)}", flush=True)
    seconds = time.perf_counter() - started
    print(
        f"  {kind}: done in {seconds:.0f} s (slowest input {slowest:.2f} s, peak RSS "
        f"{peak / 2**20:.0f} MiB)",
        flush=True,
    )
    return {
        "kind": kind,
        "counts": dict(counts),
        "examples": examples,
        "seconds": round(seconds, 1),
        "peak_rss_mib": round(peak / 2**20),
    }


def _peak_rss() -> int:
    """The process's peak resident set so far, bytes (Linux reports KiB). No input peaks
    above it: a peak below 1 GiB bounds every input's; an input that raises it past 1 GiB
    is counted as :data:`BIG`."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _save(
    outcome: Outcome, out: Path, seed: int, note: str = "", label: str = WARNED
) -> dict[str, object]:
    where = out / outcome.kind
    where.mkdir(parents=True, exist_ok=True)
    path = where / f"{label if note else outcome.label}-{outcome.index}{outcome.suffix}"
    path.write_bytes(outcome.data)
    replay = (
        f"python benchmarks/fuzz_inputs.py --replay {outcome.kind} {outcome.index} --seed {seed}"
    )
    path.with_suffix(".txt").write_text(
        f"kind: {outcome.kind}\nindex: {outcome.index}\noutcome: {outcome.label}\n"
        f"mutations: {list(outcome.mutations)}\nseconds: {outcome.seconds:.3f}\n"
        f"detail: {outcome.detail}\nreplay: {replay}\n"
    )
    detail = f"{outcome.label}; {label}: {note}" if note else outcome.detail
    detail = detail if len(detail) < 600 else detail[:600] + " …"
    return {
        "index": outcome.index,
        "mutations": list(outcome.mutations),
        "detail": detail,
        "file": str(path),
    }


def _replay(kind: str, index: int, seed: int, out: Path, budget: float) -> Outcome:
    fuzzer = Fuzzer(out / "work" / kind, budget=budget)
    (outcome,) = fuzzer.fuzz(kind, seed, 1, start=index)
    path = out / f"replay-{kind}-{index}{outcome.suffix}"
    path.write_bytes(outcome.data)
    print(f"input: {path}\nmutations: {list(outcome.mutations)}")
    return outcome


def _limit_memory(gib: float) -> None:
    """A mutated input that makes a reader allocate without bound fails (MemoryError, a
    traceback) instead of swapping the shared machine."""
    limit = int(gib * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    with_nice = getattr(os, "nice", None)
    if with_nice is not None:
        with_nice(5)  # a long run yields to interactive work


if __name__ == "__main__":
    sys.exit(main())
