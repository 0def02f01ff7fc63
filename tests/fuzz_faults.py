"""The fault kinds of the fuzz suite (issue 32), beside the input kinds of ``fuzz_support``:

* ``manifest-special`` — a batch manifest whose input cells name special files: a FIFO, a
  socket, ``/dev/zero``, ``/dev/null``, a directory, a symlink to a FIFO, a dangling
  symlink, a symlink loop, a file that vanished, an empty file. Run as ``gyropipe batch``
  treats its inputs before a well runs: the manifest read, each input fingerprinted (the
  step that hung on a FIFO) and read as stations.
* ``ledger`` — a finished batch's ledger and published markers corrupted: rows edited with
  sqlite3 (reasons that are not JSON, a fingerprint of other keys, text in ``wall_time_s``,
  a status outside the CHECK, invalid UTF-8, a dangling batch, a row deleted), the ledger
  file truncated or flipped, ``batch.json`` or a well's ``run.json`` emptied, garbled or
  deleted. Run through ``gyropipe status`` (text and JSON), ``history`` and ``batch``
  again.
* ``fs-fault`` — ``convert``, ``simulate``, ``budget`` and ``run`` with an output under a
  regular file (ENOTDIR), under ``/proc`` (refused by the kernel), in a file system that is
  full (``RLIMIT_FSIZE``: a write past the limit fails with EFBIG, as ENOSPC would), or an
  input that vanished or is a directory.

Each input is bytes (a manifest, or the JSON list of faults made) so it is saved and
replayed as the other kinds are. An outcome is one of ``fuzz_support``'s: a command that
exits 0 is accepted, one that prints one ``error:`` line naming a file is refused; an
exception out of the command is a traceback, an error over several lines or naming no file
is unlocated.
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import resource
import shutil
import signal
import socket
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from pipeline.errors import GyropipeError
from pipeline.registry import Registry
from tests_support import ROOT, CliResult, gyropipe_cli, stage, survey_stages, write_pipeline

MANIFEST_SPECIAL = "manifest-special"
LEDGER = "ledger"
FS_FAULT = "fs-fault"
FAULT_KINDS = (MANIFEST_SPECIAL, LEDGER, FS_FAULT)

STATIONS = ROOT / "examples" / "stations-j-well.csv"
PLAN = ROOT / "examples" / "plans" / "vertical.yaml"
SPECIALS = (
    "fifo", "socket", "/dev/zero", "/dev/null", "/dev/urandom", "directory", "link-to-fifo",
    "dangling-link", "link-loop", "vanished", "empty", "proc-status",
)  # fmt: skip
SQL_FAULTS = (
    ("runs", "reasons", "'not json'"),
    ("runs", "reasons", "'{\"a\": 1}'"),
    ("runs", "fingerprint", "'{\"other\": 1}'"),
    ("runs", "fingerprint", "'[1'"),
    ("runs", "wall_time_s", "'abc'"),
    ("runs", "status", "'bogus'"),
    ("runs", "inputs", "CAST(x'ff00fe' AS TEXT)"),
    ("runs", "outputs", "'{}'"),
    ("runs", "calibration", "'nope'"),
    ("runs", "versions", "'null'"),
    ("runs", "batch", "999"),
    ("runs", "started", "'yesterday'"),
    ("runs", "well", "CAST(x'c328' AS TEXT)"),
    ("runs", "out_dir", "'/nonexistent/dir'"),
    ("runs", "peak_rss_bytes", "'many'"),
    ("batches", "status", "'bogus'"),
    ("batches", "counts", "'[]'"),
    ("batches", "options", "'not json'"),
    ("batches", "heartbeat", "'soon'"),
    ("batches", "key", "NULL"),
)
MARKER_FAULTS = ("empty-object", "garbage", "truncate", "delete", "drop-sizes", "list")
FILE_FAULTS = ("truncate-ledger", "flip-ledger", "empty-ledger", "ledger-is-dir", "delete-row")
COMMANDS = ("convert", "simulate", "budget", "run")
FS_FAULTS = ("under-file", "under-proc", "full", "vanished-input", "input-is-dir")
FULL_BYTES = 4096
"""The file size limit of a 'full' file system: a few kB, so every output write fails."""


def make_fault(kind: str, rng: random.Random, seed_manifest: bytes) -> tuple[bytes, str]:
    """The bytes of one input of a fault kind and what was made."""
    if kind == MANIFEST_SPECIAL:
        lines = seed_manifest.decode().splitlines()
        special = rng.choice(SPECIALS)
        row = rng.randrange(1, len(lines))
        cells = lines[row].split(",")
        cells[1] = f"@{special}"
        lines[row] = ",".join(cells)
        return ("\n".join(lines) + "\n").encode(), f"special-{special}@{row + 1}"
    if kind == LEDGER:
        faults: list[list[Any]] = []
        for _ in range(rng.choice([1, 1, 2, 3])):
            family = rng.choice(["sql", "sql", "sql", "marker", "file"])
            if family == "sql":
                faults.append(["sql", *rng.choice(SQL_FAULTS)])
            elif family == "marker":
                faults.append(["marker", rng.choice(["batch", "run"]), rng.choice(MARKER_FAULTS)])
            else:
                faults.append(["file", rng.choice(FILE_FAULTS), rng.randrange(1 << 16)])
        return json.dumps(faults).encode(), "+".join(f"{f[0]}-{f[1]}-{f[2]}" for f in faults)
    command, fault = rng.choice(COMMANDS), rng.choice(FS_FAULTS)
    return json.dumps([command, fault]).encode(), f"{command}-{fault}"


class Faults:
    """Runs the fault kinds' inputs in ``work`` (the ledger seed: one small batch, made
    the first time a ledger input runs)."""

    def __init__(self, work: Path, registry: Registry) -> None:
        self.work = work
        self.registry = registry
        self._batch: Path | None = None

    def run(self, kind: str, data: bytes, index: int) -> tuple[str, str]:
        case = self.work / f"case-{index}"
        shutil.rmtree(case, ignore_errors=True)
        case.mkdir(parents=True)
        try:
            if kind == MANIFEST_SPECIAL:
                return self._manifest(case, data.decode())
            if kind == LEDGER:
                return self._ledger(case, json.loads(data))
            command, fault = json.loads(data)
            return self._fs(case, command, fault)
        finally:
            with contextlib.suppress(OSError):
                for path in case.rglob("*"):
                    if path.is_dir() and not path.is_symlink():
                        path.chmod(0o755)
            shutil.rmtree(case, ignore_errors=True)

    # -- special files in a manifest

    def _manifest(self, case: Path, text: str) -> tuple[str, str]:
        from pipeline.batch.jobs import jobs_from_manifest
        from pipeline.convert import read_kind
        from pipeline.hashing import sha256_file
        from pipeline.well import WellMetadata

        shutil.copy(STATIONS, case / "a.csv")
        for special in SPECIALS:
            if f"@{special}" in text:
                text = text.replace(f"@{special}", str(_special(case, special)))
        manifest = case / "wells.csv"
        manifest.write_text(text)
        try:
            jobs = jobs_from_manifest(manifest, ("stations",), WellMetadata())
        except GyropipeError as exc:
            return _refused_or_unlocated(str(exc), [manifest])
        details = []
        for job in jobs:
            path = job.inputs["stations"]
            try:
                sha256_file(path)  # the batch's fingerprint: the well fails before reading
            except OSError as exc:
                details.append(f"fingerprint refused {path.name}: {exc.strerror}")
                continue
            try:
                read_kind(self.registry, path, kind="stations", reader="auto", options={})
            except GyropipeError as exc:
                label, detail = _refused_or_unlocated(str(exc), [path])
                if label != "refused":
                    return label, detail
                details.append(detail)
        return "accepted", f"{len(jobs)} wells; " + "; ".join(details)

    # -- a corrupted ledger

    def _seed_batch(self) -> Path:
        """A finished batch of two wells (made once)."""
        if self._batch is None:
            seed = self.work / "ledger-seed"
            shutil.rmtree(seed, ignore_errors=True)
            (seed / "in").mkdir(parents=True)
            for name in ("A-1", "B-2"):
                shutil.copy(STATIONS, seed / "in" / f"{name}.csv")
            trajectory = {"table": "trajectory.trajectory"}
            stages = [
                *survey_stages(),
                stage("export_csv", "write", trajectory, writer="csv", filename="t.csv"),
            ]
            pipeline = write_pipeline(seed, stages, name="survey")
            done = gyropipe_cli(
                "batch", pipeline, "--inputs", seed / "in" / "*.csv", "--out", seed / "out",
                "--workers", "1",
            )  # fmt: skip
            assert done.returncode == 0, done.output
            self._batch = seed
        return self._batch

    def _ledger(self, case: Path, faults: list[list[Any]]) -> tuple[str, str]:
        seed = self._seed_batch()
        shutil.copytree(seed, case / "b", symlinks=True)
        root = case / "b"
        out = root / "out"
        for fault in faults:
            # a fault an earlier one undid (SQLite's message about a damaged name: not text)
            with contextlib.suppress(sqlite3.Error, OSError, UnicodeDecodeError):
                _corrupt(out, fault)
        pipeline = root / "survey.yaml"
        commands: list[tuple[str | Path, ...]] = [
            ("status", out),
            ("status", out, "--json"),
            ("history", "A-1", "--dir", out),
            ("history", "B-2", "--dir", out, "--json"),
            ("batch", pipeline, "--inputs", root / "in" / "*.csv", "--out", out, "--workers", "1"),
        ]
        shown = []
        for command in commands:
            label, detail = cli_outcome(gyropipe_cli(*command), [out])
            if label not in ("accepted", "refused"):
                return label, f"{command[0]}: {detail}"
            shown.append(f"{command[0]} {label}")
        return ("refused" if any("refused" in s for s in shown) else "accepted"), ", ".join(shown)

    # -- file-system faults

    def _fs(self, case: Path, command: str, fault: str) -> tuple[str, str]:
        source = case / "stations.csv"
        shutil.copy(STATIONS, source)
        base = case
        if fault == "under-file":
            (case / "file").write_text("a file, not a directory")
            base = case / "file"
        elif fault == "under-proc":
            base = Path("/proc/self/gyropipe-fuzz")
        elif fault == "vanished-input":
            source = case / "gone.csv"
        elif fault == "input-is-dir":
            source = case / "dir.csv"
            source.mkdir()
        plan = PLAN if not fault.endswith("input") and fault != "input-is-dir" else source
        args: tuple[str | Path, ...] = {
            "convert": ("convert", source, base / "out.parquet"),
            "simulate": ("simulate", plan, "--out", base / "sim"),
            "budget": ("budget", plan, "--out", base / "budget.csv"),
            "run": ("run", ROOT / "pipelines/survey.yaml", "--input", source, "--out", base / "o"),
        }[command]
        with _full_disk(fault == "full"):
            result = gyropipe_cli(*args)
        return cli_outcome(result, [Path(a) for a in args if isinstance(a, Path)])


def _special(case: Path, special: str) -> Path:
    """Make the special file ``special`` in ``case``; returns its path."""
    if special.startswith("/dev/"):
        return Path(special)
    path = case / f"special-{special.replace('/', '-')}.csv"
    if special == "fifo":
        os.mkfifo(path)
    elif special == "socket":
        server = socket.socket(socket.AF_UNIX)
        server.bind(str(path))  # left bound: the socket file stays
        _SOCKETS.append(server)
    elif special == "directory":
        path.mkdir()
    elif special == "link-to-fifo":
        os.mkfifo(case / "target-fifo")
        path.symlink_to(case / "target-fifo")
    elif special == "dangling-link":
        path.symlink_to(case / "missing.csv")
    elif special == "link-loop":
        path.symlink_to(path)
    elif special == "empty":
        path.write_bytes(b"")
    elif special == "proc-status":
        return Path("/proc/self/status")
    return path  # "vanished": never made


_SOCKETS: list[socket.socket] = []


def _corrupt(out: Path, fault: list[Any]) -> None:
    """Apply one ledger fault (see the module docstring) to the batch output ``out``."""
    ledger = out / "ledger.sqlite"
    family, what, arg = fault[0], fault[1], fault[2]
    if family == "sql":
        with contextlib.closing(sqlite3.connect(ledger)) as db:
            db.execute("PRAGMA ignore_check_constraints = ON")
            db.execute("PRAGMA foreign_keys = OFF")
            with contextlib.suppress(sqlite3.IntegrityError):  # NOT NULL: not made
                db.execute(f"UPDATE {what} SET {arg} = {fault[3] if len(fault) > 3 else arg}")
            db.commit()
        return
    if family == "marker":
        markers = sorted(out.glob("batch.json" if what == "batch" else "*/run.json"))
        markers = markers or sorted(out.glob("**/batch.json"))
        for marker in markers[:1]:
            _garble_json(marker, arg)
        return
    if what == "delete-row":
        with contextlib.closing(sqlite3.connect(ledger)) as db:
            db.execute("PRAGMA foreign_keys = OFF")
            db.execute("DELETE FROM batches WHERE id = (SELECT min(id) FROM batches)")
            db.commit()
    elif what == "truncate-ledger":
        size = ledger.stat().st_size
        with ledger.open("r+b") as fh:
            fh.truncate(arg % max(size, 1))
    elif what == "flip-ledger":
        data = bytearray(ledger.read_bytes())
        if not data:  # emptied by an earlier edit
            return
        data[arg % len(data)] ^= 0xFF
        ledger.write_bytes(bytes(data))
    elif what == "empty-ledger":
        ledger.write_bytes(b"")
    elif what == "ledger-is-dir":
        ledger.unlink()
        ledger.mkdir()
        (ledger / "x").write_text("x")


def _garble_json(path: Path, how: str) -> None:
    if how == "delete":
        path.unlink()
        return
    text = path.read_bytes().decode("utf-8", errors="replace")  # an earlier edit may garble it
    if how == "empty-object":
        path.write_text("{}")
    elif how == "garbage":
        path.write_bytes(b"\xff\xfe not json")
    elif how == "truncate":
        path.write_text(text[: len(text) // 2])
    elif how == "list":
        path.write_text("[]")
    else:  # drop-sizes: the run's files without their byte counts
        try:
            data = json.loads(text)
        except ValueError:  # an earlier edit left no JSON to edit
            return
        for entry in data.get("files", []) if isinstance(data, dict) else []:
            if isinstance(entry, dict):
                entry.pop("bytes", None)
                entry.pop("size", None)
        if isinstance(data, dict):
            data.pop("sizes", None)
        path.write_text(json.dumps(data))


@contextlib.contextmanager
def _full_disk(full: bool) -> Iterator[None]:
    """While active, a write past :data:`FULL_BYTES` fails (EFBIG) as on a full disk."""
    if not full:
        yield
        return
    previous = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FULL_BYTES, previous[1]))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, previous)
        signal.signal(signal.SIGXFSZ, handler)


def cli_outcome(result: CliResult, paths: list[Path]) -> tuple[str, str]:
    """The outcome of a ``gyropipe`` command (its exception, if any, is raised by
    :func:`gyropipe_cli` and classified by the fuzzer as a traceback)."""
    if result.returncode == 0:
        return "accepted", f"exit 0{'; warned' if 'warning:' in result.stderr else ''}"
    lines = result.stderr.splitlines()
    errors = _error_block(lines)
    if "Traceback" in result.stderr:
        return "traceback", f"exit {result.returncode}: {result.stderr.strip()[-600:]}"
    failed = [e for e in map(_event, lines) if e.get("status") == "failed"]
    if not errors and failed:  # a batch: each failed well says why in its event
        unexplained = [e for e in failed if not e.get("detail")]
        label = "unlocated" if unexplained else "refused"
        return label, " | ".join(f"{e.get('well')}: {e.get('detail')}" for e in failed)[:600]
    if not errors:
        return "traceback", f"exit {result.returncode}: {result.stderr.strip()[-600:]}"
    return _refused_or_unlocated("\n".join(errors), paths)


def _error_block(lines: list[str]) -> list[str]:
    """The ``error:`` lines (click's ``Error:`` too) and the indented problems each lists."""
    block: list[str] = []
    for line in lines:
        if line.startswith(("error:", "Error:")) or (block and line.startswith("  ")):
            block.append(line)
    return block


def _event(line: str) -> dict[str, Any]:
    """A batch's progress event (a JSON line on stderr), else {}."""
    if not line.startswith("{"):
        return {}
    try:
        event = json.loads(line)
    except ValueError:
        return {}
    return event if isinstance(event, dict) and event.get("event") == "well" else {}


def _refused_or_unlocated(message: str, paths: list[Path]) -> tuple[str, str]:
    """Refused if ``message`` (an error and the problems it lists) names a file (one of
    ``paths``, or any absolute path), else unlocated."""
    lines = [line for line in message.strip().splitlines() if line.strip()] or [""]
    named = any(p.name in message for p in paths) or "/" in message
    return ("refused" if named else "unlocated"), " | ".join(lines)[:600]
