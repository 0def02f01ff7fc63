"""The ``gyropipe`` command.

Exit codes: 0 success; 1 the run failed (bad input data, a stage raised, a contract was
broken); 2 the pipeline, its configuration or the command line is invalid; 3 the run
succeeded and published its outputs but the survey failed an acceptance gate (``run.json``
``status: rejected``; a batch: some well was rejected, none failed).

Only click and the standard library are imported here: each command imports what it uses
(numpy, pyarrow, pydantic, the plugins) when it runs, so ``gyropipe --help`` stays fast.
"""

from __future__ import annotations

import contextlib
import json
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import click

from pipeline.cli_args import disable_option, input_files, reader_options, well_overrides
from pipeline.cli_models import models
from pipeline.errors import FileSystemError, GyropipeError, ReaderOptionsError, SpecError
from pipeline.version import __version__

if TYPE_CHECKING:
    import pyarrow as pa

    from pipeline.batch.ledger import Ledger
    from pipeline.graph import Plan
    from pipeline.registry import Registry

EXIT_FAILED = 1
EXIT_CONFIG = 2
EXIT_REJECTED = 3

set_option = click.option(
    "--set",
    "overrides",
    multiple=True,
    metavar="STAGE.PARAM=VALUE",
    help="Override a stage parameter (value parsed as YAML). Repeatable.",
)


def _registry(disabled: tuple[str, ...]) -> Registry:
    """The registry of this process (:func:`~pipeline.plugins.shared_registry`), its
    plugins' problems shown as warnings."""
    registry = _registry_quiet(disabled)
    for problem in registry.problems:
        click.echo(f"warning: {problem}", err=True)
    return registry


def _plan(pipeline_file: str, overrides: tuple[str, ...], registry: Registry) -> Plan:
    from pipeline.graph import build_plan
    from pipeline.spec import load_spec

    try:
        return build_plan(load_spec(pipeline_file, list(overrides)), registry)
    except SpecError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_CONFIG)


class _Commands(click.Group):
    """The command group: a file-system failure that no command reported itself (disk full,
    read-only, permission, a file gone) is one located line and exit 1, never a traceback."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except OSError as exc:
            click.echo(f"error: {FileSystemError.of(exc, 'access')}", err=True)
            sys.exit(EXIT_FAILED)


@click.group(cls=_Commands)
@click.version_option(__version__, prog_name="gyropipe")
def main() -> None:
    """gyropipe: gyro-survey processing pipelines."""


main.add_command(models)


@main.command()
@click.argument("pipeline_file", metavar="PIPELINE.yaml", type=click.Path(dir_okay=False))
@set_option
@disable_option
def validate(pipeline_file: str, overrides: tuple[str, ...], disabled: tuple[str, ...]) -> None:
    """Validate a pipeline without running anything."""
    plan = _plan(pipeline_file, overrides, _registry(disabled))
    click.echo(
        f"ok: pipeline {plan.spec.name!r} {plan.spec.version}: "
        + " → ".join(f"{s.id}({s.uses})" for s in plan.stages)
    )


@main.command()
@click.argument("pipeline_file", metavar="PIPELINE.yaml", type=click.Path(dir_okay=False))
@click.option(
    "--input",
    "inputs",
    multiple=True,
    required=True,
    metavar="[NAME=]FILE",
    help="A pipeline input file; NAME may be left out when the pipeline has one input.",
)
@click.option(
    "--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory."
)
@click.option(
    "--well",
    "well_items",
    multiple=True,
    metavar="FIELD=VALUE",
    help="Override a well metadata field (e.g. latitude=61.25). Repeatable.",
)
@set_option
@disable_option
def run(
    pipeline_file: str,
    inputs: tuple[str, ...],
    out_dir: str,
    well_items: tuple[str, ...],
    overrides: tuple[str, ...],
    disabled: tuple[str, ...],
) -> None:
    """Run a pipeline on one well's input files."""
    from pipeline.lazy_pandas import defer_pandas

    defer_pandas()
    from pipeline.api.run import execute
    from pipeline.cli_run import qc_lines, verdict_line, warnings_echoed
    from pipeline.manifest import REJECTED
    from pipeline.qc.gates import acceptance_lines
    from pipeline.runner import RunInputError
    from pipeline.streams import use_returning_memory_pool

    use_returning_memory_pool()
    registry = _registry(disabled)
    plan = _plan(pipeline_file, overrides, registry)
    try:
        files = input_files(plan, inputs)
        well = well_overrides(well_items)
    except (click.BadParameter, RunInputError) as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_CONFIG)
    try:
        with warnings_echoed():
            result = execute(plan, registry, files, well=well, out=Path(out_dir))
    except RunInputError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_CONFIG)
    except GyropipeError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    for stage in result.manifest["stages"]:
        rows = ", ".join(f"{p}={n}" for p, n in stage["rows_out"].items()) or "-"
        click.echo(f"  {stage['id']:<16} {stage['wall_time_s'] * 1e3:9.1f} ms  {rows}")
    for line in qc_lines(plan, result):
        click.echo(line)
    for line in acceptance_lines(result.manifest):
        click.echo(line)
    for path in result.outputs:
        click.echo(f"wrote {path}")
    click.echo(verdict_line(plan, result, Path(out_dir) / "run.json"))
    if result.manifest["status"] == REJECTED:
        sys.exit(EXIT_REJECTED)


@main.command()
@click.argument("pipeline_file", metavar="PIPELINE.yaml", type=click.Path(dir_okay=False))
@click.option(
    "--inputs",
    "inputs_glob",
    metavar="GLOB",
    help="One well per matching file (id: file name without extension); one-input pipelines.",
)
@click.option(
    "--manifest",
    type=click.Path(dir_okay=False),
    help="CSV: well_id, one column per pipeline input, header fields (latitude, …).",
)
@click.option(
    "--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory."
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Parallel wells (default: the number of CPUs).",
)
@click.option(
    "--executor",
    metavar="NAME",
    default="local",
    show_default=True,
    help="A registered executor (gyropipe plugins lists them): local, a process pool; dask, "
    "a Dask distributed cluster (extra 'dask'); or one a plugin adds.",
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Scheduler address for an executor that takes one (dask; default: a LocalCluster "
    "on 127.0.0.1).",
)
@click.option("--only-changed", is_flag=True, help="Skip wells whose run would be unchanged.")
@click.option("--rerun-failed", is_flag=True, help="Run only wells whose last run failed.")
@click.option(
    "--ledger",
    "ledger_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="Run ledger (default: OUT/ledger.sqlite).",
)
@click.option("--quiet", is_flag=True, help="No progress bar or table: JSON log lines on stderr.")
@click.option(
    "--well",
    "well_items",
    multiple=True,
    metavar="FIELD=VALUE",
    help="Header field for every well (a manifest column overrides it). Repeatable.",
)
@set_option
@disable_option
def batch(
    pipeline_file: str,
    inputs_glob: str | None,
    manifest: str | None,
    out_dir: str,
    workers: int | None,
    executor: str,
    scheduler: str | None,
    only_changed: bool,
    rerun_failed: bool,
    ledger_file: str | None,
    quiet: bool,
    well_items: tuple[str, ...],
    overrides: tuple[str, ...],
    disabled: tuple[str, ...],
) -> None:
    """Run a pipeline on many wells: one run per well into OUT/<well_id>/, recorded in a
    run ledger. Exit 0 all wells done or skipped, 1 some failed, 2 configuration error,
    3 none failed but some rejected (a survey failed an acceptance gate)."""
    from pipeline.lazy_pandas import defer_pandas

    defer_pandas()
    from pipeline.api.batch import run_batch
    from pipeline.batch.jobs import BatchConfigError
    from pipeline.batch.ledger import LedgerError
    from pipeline.batch.summary import table_text
    from pipeline.streams import use_returning_memory_pool

    use_returning_memory_pool()

    def config_error(message: str) -> NoReturn:
        click.echo(f"error: {message}", err=True)
        sys.exit(EXIT_CONFIG)

    if (inputs_glob is None) == (manifest is None):
        config_error("give either --inputs GLOB or --manifest FILE")
    _registry(disabled)  # its plugins' problems shown once, as warnings
    try:
        defaults = well_overrides(well_items)
    except click.BadParameter as exc:
        config_error(str(exc))
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        report = run_batch(
            pipeline_file,
            inputs_glob,
            out=out_dir,
            manifest=manifest,
            workers=workers,
            executor=executor,
            scheduler=scheduler,
            only_changed=only_changed,
            rerun_failed=rerun_failed,
            ledger=ledger_file,
            set=overrides,
            well=defaults,
            disable=disabled,
            progress=not quiet,
        )
    except (LedgerError, FileSystemError) as exc:  # not a configuration: exit 1
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    except (SpecError, BatchConfigError, ImportError, OSError) as exc:
        config_error(str(exc))
    except KeyboardInterrupt:
        click.echo("interrupted: run the same command again to resume", err=True)
        sys.exit(EXIT_FAILED)
    finally:
        signal.signal(signal.SIGTERM, previous)
    if not quiet:
        click.echo(table_text(report.results))
        click.echo(f"summary: {', '.join(map(str, report.summary_files))}")
    sys.exit(report.exit_code)


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def _registry_quiet(disabled: tuple[str, ...]) -> Registry:
    """The plugins, their problems left to the caller to show."""
    from pipeline.plugins import shared_registry

    return shared_registry(disabled)


def _open_ledger(out_dir: str, ledger_file: str | None) -> Ledger:
    from pipeline.batch.jobs import LEDGER, BatchConfigError
    from pipeline.batch.ledger import Ledger, LedgerError

    path = Path(ledger_file) if ledger_file else Path(out_dir) / LEDGER
    if not path.is_file():
        click.echo(f"error: no ledger at {path}", err=True)
        sys.exit(EXIT_CONFIG)
    try:
        return Ledger(path)
    except (BatchConfigError, LedgerError) as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_CONFIG)


@contextlib.contextmanager
def _reading(ledger: Ledger) -> Iterator[None]:
    """Read ``ledger``: the rows that do not parse told as warnings, a failing ledger one
    line and exit 1; closed after."""
    from pipeline.batch.ledger import LedgerError

    try:
        yield
    except LedgerError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    finally:
        for problem in ledger.problems:
            click.echo(f"warning: {problem}", err=True)
        ledger.close()


ledger_option = click.option(
    "--ledger",
    "ledger_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="Ledger file (default: DIR/ledger.sqlite).",
)
json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON.")


@main.command()
@click.argument("out_dir", metavar="DIR", type=click.Path(file_okay=False))
@ledger_option
@json_option
@click.option(
    "--html",
    "html_file",
    is_flag=False,
    flag_value="",
    default=None,
    metavar="[FILE]",
    type=click.Path(dir_okay=False),
    help="Write the fleet page (one HTML page of every well, failing wells first) to FILE "
    "(default: DIR/fleet.html) and print its path.",
)
def status(out_dir: str, ledger_file: str | None, as_json: bool, html_file: str | None) -> None:
    """Batches and the latest run of every well in a batch output directory."""
    from pipeline.batch.views import status_document, status_text

    if html_file is not None and as_json:
        raise click.UsageError("--html writes the fleet page, --json prints JSON: give one")
    ledger = _open_ledger(out_dir, ledger_file)
    if html_file is not None:
        from pipeline.batch.fleet_page import FLEET_PAGE, fleet_title, write_fleet_page
        from pipeline.batch.views import status_fleet

        with _reading(ledger):
            fleet = status_fleet(ledger, fleet_title(Path(out_dir)))
        try:
            page = write_fleet_page(fleet, Path(html_file or Path(out_dir) / FLEET_PAGE))
        except GyropipeError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(EXIT_FAILED)
        click.echo(str(page))
        return
    with _reading(ledger):
        text = json.dumps(status_document(ledger), indent=2) if as_json else status_text(ledger)
    click.echo(text)


@main.command()
@click.argument("well_id", metavar="WELL")
@click.option(
    "--dir",
    "out_dir",
    default=".",
    show_default=True,
    type=click.Path(file_okay=False),
    help="Batch output directory holding ledger.sqlite.",
)
@ledger_option
@json_option
def history(well_id: str, out_dir: str, ledger_file: str | None, as_json: bool) -> None:
    """Every recorded run of one well: why it ran, inputs, versions, calibration, result."""
    from pipeline.batch.views import history_document, history_text

    ledger = _open_ledger(out_dir, ledger_file)
    with _reading(ledger):
        runs = ledger.history(well_id)
    if not runs:
        click.echo(f"error: no runs of well {well_id!r} in {ledger.path}", err=True)
        sys.exit(EXIT_CONFIG)
    if as_json:
        click.echo(json.dumps(history_document(well_id, runs), indent=2))
    else:
        click.echo(history_text(well_id, runs))


@main.command()
@disable_option
def plugins(disabled: tuple[str, ...]) -> None:
    """List plugins, their versions and what each provides."""
    registry = _registry_quiet(disabled)
    for info in registry.plugins.values():
        kind = "built-in" if info.builtin else "third-party"
        status = f"FAILED: {info.error}" if info.error else ", ".join(info.provides) or "nothing"
        click.echo(f"{info.name} {info.version} ({kind}): {status}")
    if registry.readers:
        click.echo("readers (reader: auto takes the surest claim; third-party wins a tie):")
    for name, (reader, owner) in sorted(registry.readers.items()):
        kinds = ", ".join(reader.kinds)
        claims = reader.what_it_claims()
        click.echo(f"  {name} ({registry.plugin_label(owner)}) reads {kinds}: {claims}")
    if registry.executors:
        click.echo("executors (gyropipe batch --executor NAME):")
    for name, (runner, owner) in sorted(registry.executors.items()):
        click.echo(f"  {name} ({registry.plugin_label(owner)}): {runner.description}")
    for problem in registry.problems:
        click.echo(f"problem: {problem}")


@main.command()
@click.option(
    "--out", "out_dir", default="schemas", show_default=True, type=click.Path(file_okay=False)
)
@click.option(
    "--docs", "docs_dir", default="docs", show_default=True, type=click.Path(file_okay=False)
)
@click.option("--check", is_flag=True, help="Only check the files are up to date (exit 1 if not).")
def schemas(out_dir: str, docs_dir: str, check: bool) -> None:
    """Write the JSON Schemas of the pipeline YAML, well metadata and table contracts, and
    the tables page (docs/tables.md)."""
    from pipeline import schemas as schema_files

    registry = _registry_quiet(())
    if check:
        stale = schema_files.stale(registry, Path(out_dir), Path(docs_dir))
        for path in stale:
            click.echo(f"stale: {path}")
        sys.exit(EXIT_FAILED if stale else 0)
    for path in schema_files.write(registry, Path(out_dir), Path(docs_dir)):
        click.echo(f"wrote {path}")


@main.command()
@click.argument("plan_file", metavar="PLAN.yaml", type=click.Path(dir_okay=False))
@click.option(
    "--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory."
)
@click.option("--seed", type=int, default=None, help="Random seed (default: the plan's).")
@click.option(
    "--format",
    "writer_name",
    default="parquet",
    show_default=True,
    help="Registered writer for the tables (parquet, csv, …).",
)
def simulate(plan_file: str, out_dir: str, seed: int | None, writer_name: str) -> None:
    """Simulate a gyro survey: raw sensor samples, truth and stations."""
    from pipeline.lazy_pandas import defer_pandas

    defer_pandas()
    from pipeline.atomic import atomic_path, atomic_write_bytes
    from pipeline.hashing import sha256_file
    from pipeline.sim.spec import load_simulation
    from pipeline.stages.simulation import simulation_tables, well_of_simulation

    registry = _registry(())
    try:
        writer = registry.writers[writer_name][0]
    except KeyError:
        click.echo(
            f"error: no writer named {writer_name!r} "
            f"(installed: {', '.join(sorted(registry.writers))})",
            err=True,
        )
        sys.exit(EXIT_CONFIG)
    with _plan_errors(plan_file):
        spec = load_simulation(plan_file, seed=seed, read_stations=_stations_reader(registry))
        started = time.perf_counter()
        tables = simulation_tables(spec)
    wall = time.perf_counter() - started
    out = Path(out_dir)
    well = well_of_simulation(spec)
    outputs = {}
    for name, table in tables.items():
        path = out / f"{name}.{writer.extension}"
        with atomic_path(path) as tmp:
            writer.write(table, tmp, well)
        outputs[name] = {"file": path.name, "rows": table.num_rows}
        click.echo(f"wrote {path} ({table.num_rows} rows)")
    manifest = {
        "gyropipe": __version__,
        "plan": {"file": plan_file, "sha256": sha256_file(Path(plan_file))},
        "seed": spec.seed,
        "wall_time_s": round(wall, 3),
        "outputs": outputs,
    }
    atomic_write_bytes(out / "simulation.json", json.dumps(manifest, indent=2).encode())


@main.command()
@click.argument("plan_file", metavar="PLAN.yaml", type=click.Path(dir_okay=False))
@click.option(
    "--out",
    "out_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="Also write the budget table to this file (.csv or .parquet).",
)
def budget(plan_file: str, out_file: str | None) -> None:
    """Predict the 1σ inclination and azimuth error at each station of a point survey."""
    from pipeline.atomic import atomic_path
    from pipeline.sim.budget import budget_lines, error_budget
    from pipeline.sim.spec import load_simulation
    from pipeline.stages.simulation import well_of_simulation

    with _plan_errors(plan_file):
        spec = load_simulation(plan_file, read_stations=_stations_reader())
        table = error_budget(spec)
    click.echo(f"{spec.name}: tool {spec.tool.preset}, latitude {spec.site.latitude}°")
    click.echo("\n".join(budget_lines(table)))
    if out_file:
        registry = _registry_quiet(())
        ext = Path(out_file).suffix.lstrip(".")
        writers = [w for w, _ in registry.writers.values() if w.extension == ext]
        if not writers:
            click.echo(f"error: no writer for .{ext} files", err=True)
            sys.exit(EXIT_CONFIG)
        with atomic_path(Path(out_file)) as tmp:
            writers[0].write(table, tmp, well_of_simulation(spec))
        click.echo(f"wrote {out_file}")


@main.command()
@click.argument("input_file", metavar="INPUT", type=click.Path(dir_okay=False))
@click.argument("output_file", metavar="[OUTPUT]", required=False, type=click.Path(dir_okay=False))
@click.option(
    "--out",
    "out_file",
    type=click.Path(dir_okay=False),
    help="Output file; its extension chooses the format (.parquet, .csv, .las, .mcap…).",
)
@click.option(
    "--kind",
    type=click.Choice(["auto", "stations", "samples", "readings", "log"]),
    default="auto",
    show_default=True,
    help="What the input holds (auto: a survey kind if it is one, else a log).",
)
@click.option(
    "--reader",
    "reader_name",
    default="auto",
    show_default=True,
    help="Reader name, or auto to sniff the input.",
)
@click.option(
    "--option",
    "options",
    multiple=True,
    metavar="KEY=VALUE",
    help="Reader option (value parsed as YAML), e.g. units={md: ft}. Repeatable.",
)
@click.option(
    "--well",
    "well_items",
    multiple=True,
    metavar="FIELD=VALUE",
    help="Override a well metadata field. Repeatable.",
)
@disable_option
def convert(
    input_file: str,
    output_file: str | None,
    out_file: str | None,
    kind: str,
    reader_name: str,
    options: tuple[str, ...],
    well_items: tuple[str, ...],
    disabled: tuple[str, ...],
) -> None:
    """Convert INPUT to the format of --out's extension (Parquet, CSV, LAS, MCAP): survey
    stations and samples in gyropipe's units and frames, a well log's curves as logged."""
    from pipeline.lazy_pandas import defer_pandas

    defer_pandas()
    from pipeline.convert import convert as convert_file
    from pipeline.errors import InputFileWarning

    if output_file and out_file and Path(output_file) != Path(out_file):
        click.echo(f"error: two outputs given: {output_file} and --out {out_file}", err=True)
        sys.exit(EXIT_CONFIG)
    target = out_file or output_file
    if not target:
        click.echo("error: no output file: give --out OUTPUT", err=True)
        sys.exit(EXIT_CONFIG)
    registry = _registry(disabled)
    failure: tuple[int, Exception] | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", InputFileWarning)
        try:
            parsed = reader_options(options)
            well = well_overrides(well_items)
            done = convert_file(
                registry,
                Path(input_file),
                Path(target),
                kind=kind,
                reader=reader_name,
                options=parsed,
                well=well,
            )
        except (click.BadParameter, ValueError, ReaderOptionsError) as exc:
            failure = (EXIT_CONFIG, exc)
        except GyropipeError as exc:
            failure = (EXIT_FAILED, exc)
    for warning in caught:
        click.echo(f"warning: {warning.message}", err=True)
    if failure is not None:
        click.echo(f"error: {failure[1]}", err=True)
        sys.exit(failure[0])
    table = done.table
    click.echo(
        f"wrote {done.target}: {KIND_WORDS.get(done.kind, done.kind)}, {table.num_rows} rows × "
        f"{table.num_columns} columns ({_names(table.column_names)})"
    )


KIND_WORDS = {
    "stations": "survey stations",
    "samples": "raw sensor samples",
    "readings": "position readings",
    "log": "well log",
}


def _names(names: list[str], shown: int = 8) -> str:
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return ", ".join(names[:shown]) + more


def _stations_reader(registry: Registry | None = None) -> Callable[[Path, str], pa.Table]:
    """Reads a simulation plan's stations file with the engine's reader choice (the plugins
    are loaded only if the plan has one)."""

    def read(path: Path, reader: str) -> pa.Table:
        return (registry or _registry(())).read(path, "stations", reader=reader)[0]

    return read


@contextlib.contextmanager
def _plan_errors(plan_file: str) -> Iterator[None]:
    """Report an invalid simulation plan (or one the simulator cannot run) and exit 2."""
    try:
        yield
    except SpecError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_CONFIG)
    except (GyropipeError, ValueError) as exc:
        click.echo(f"error: {plan_file}: {exc}", err=True)
        sys.exit(EXIT_CONFIG)


if __name__ == "__main__":  # python -m pipeline.cli, as the gyropipe command
    main()
