"""Built-in plugin: the stages that bring files into a pipeline and write tables out.

Readers and writers themselves are plugins of their own (``gyropipe_register_readers``,
``gyropipe_register_writers``); these stages choose one by name or by sniffing the file.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Annotated, Any

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from pipeline.contracts import SOURCE_KEY, TableContract
from pipeline.errors import GyropipeError
from pipeline.hookspecs import hookimpl
from pipeline.registry import (
    ReaderDef,
    StageContext,
    StageDef,
    pipeline_input,
    registered,
)
from pipeline.tables import AnyTable, PositionReadings, RawSamples, Stations
from pipeline.well import attach


class ReaderChoiceError(GyropipeError):
    """No installed reader can read a file as the requested kind of table."""


class ReadParams(BaseModel):
    """Parameters of a read stage."""

    model_config = ConfigDict(extra="forbid")
    input: str = pipeline_input("stations", "name of the pipeline input to read")
    reader: Annotated[str, registered("reader", also=("auto",))] = Field(
        "auto", description="reader name, or 'auto' to sniff the file"
    )
    options: dict[str, Any] = Field(
        default_factory=dict, description="reader options (see the reader's documentation)"
    )


class WriteParams(BaseModel):
    """Parameters of the write stage."""

    model_config = ConfigDict(extra="forbid")
    writer: Annotated[str, registered("writer")] = Field(
        description="writer name (csv, parquet, …)"
    )
    filename: str | None = Field(
        None, description="output file name; default '<stage id>.<writer extension>'"
    )

    def output_path(self, ctx: StageContext, extension: str) -> Path:
        """Where the stage writes: ``filename``, or ``<stage id>.<extension>``."""
        return ctx.output_path(self.filename or f"{ctx.stage_id}.{extension}")


def choose_reader(readers: Iterable[ReaderDef], kind: str, name: str, path: Path) -> ReaderDef:
    """Among ``readers``, the one called ``name``, or with ``auto`` the first reader of
    ``kind`` that sniffs ``path`` as its own."""
    readers = list(readers)
    if name != "auto":
        found = [r for r in readers if r.name == name]
        if not found:
            raise ReaderChoiceError(
                f"no reader named {name!r} (installed: {', '.join(r.name for r in readers)})"
            )
        reader = found[0]
        if kind not in reader.kinds:
            raise ReaderChoiceError(
                f"reader {name!r} cannot read {kind} (it reads: {', '.join(reader.kinds)})"
            )
        return reader
    able = [r for r in readers if kind in r.kinds]
    for reader in able:
        if reader.sniff(path):
            return reader
    raise ReaderChoiceError(
        f"no installed reader recognises {str(path)!r} as {kind} (readers of {kind}: "
        f"{', '.join(r.name for r in able) or 'none'}); name one with `reader:`"
    )


def read_stage(
    kind: str,
) -> Callable[[Mapping[str, pa.Table], ReadParams, StageContext], dict[str, pa.Table]]:
    """Stage function reading the pipeline input into a table of ``kind``."""

    def read(
        inputs: Mapping[str, pa.Table], params: ReadParams, ctx: StageContext
    ) -> dict[str, pa.Table]:
        path = ctx.input_path(params.input)
        reader = choose_reader(ctx.readers(), kind, params.reader, path)
        options = dict(params.options)
        if "default_north_reference" in reader.options.model_fields and ctx.well.north_reference:
            options.setdefault("default_north_reference", ctx.well.north_reference)
        try:
            parsed = reader.options.model_validate(options)
        except ValidationError as exc:
            raise ReaderChoiceError(f"options of reader {reader.name!r}: {exc}") from None
        table, header = reader.read(path, kind, parsed)
        meta = {**(table.schema.metadata or {}), SOURCE_KEY: str(path).encode()}
        return {kind: attach(table.replace_schema_metadata(meta), header)}

    return read


def read_stage_def(
    name: str, kind: str, contract: type[TableContract], description: str, default_input: str
) -> StageDef:
    """A stage reading the pipeline input ``default_input`` (unless told another) into a
    table of ``kind`` on the output port ``kind``."""
    params = create_model(
        f"{kind.title().replace('_', '')}ReadParams",
        __base__=ReadParams,
        __doc__=f"Parameters of the {name} stage.",
        input=(str, pipeline_input(default_input, "name of the pipeline input to read")),
    )
    return StageDef(
        name=name,
        func=read_stage(kind),
        description=description,
        outputs={kind: contract},
        params=params,
    )


def write(
    inputs: Mapping[str, pa.Table], params: WriteParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Write the input table through the chosen writer (published when the run succeeds)."""
    writer = ctx.writer(params.writer)
    path = params.output_path(ctx, writer.extension)
    writer.write(attach(inputs["table"], ctx.well), path, ctx.well)
    return {}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    for name, kind, contract, description in (
        (
            "read_stations",
            "stations",
            Stations,
            "Read survey stations (MD, inclination, azimuth) from a pipeline input.",
        ),
        (
            "read_samples",
            "samples",
            RawSamples,
            "Read raw sensor samples (gyros, accelerometers, magnetometers) from a pipeline input.",
        ),
        (
            "read_readings",
            "readings",
            PositionReadings,
            "Read pre-averaged point-survey readings (one row per station and frame position) "
            "from a pipeline input.",
        ),
    ):
        register(read_stage_def(name, kind, contract, description, kind))
    register(
        StageDef(
            name="write",
            func=write,
            description="Write a table to a file in the output directory with a named writer.",
            inputs={"table": AnyTable},
            params=WriteParams,
        )
    )
