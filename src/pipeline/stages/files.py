"""Built-in plugin: the stages that bring files into a pipeline and write tables out.

Readers and writers themselves are plugins of their own (``gyropipe_register_readers``,
``gyropipe_register_writers``); the engine chooses the reader (:meth:`Registry.reader_for`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Annotated, Any, ClassVar

import pyarrow as pa
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ModelWrapValidatorHandler,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    create_model,
    model_validator,
)
from pydantic_core import InitErrorDetails

from pipeline.contracts import TableContract
from pipeline.errors import WrongKindError
from pipeline.filenames import OutputFilename
from pipeline.hookspecs import hookimpl
from pipeline.inputfiles import parameter_paths
from pipeline.ports import write_port
from pipeline.registry import (
    Registry,
    StageContext,
    StageDef,
    pipeline_input,
    registered,
)
from pipeline.streams import Port, TableStream
from pipeline.tables import AnyTable, PositionReadings, RawSamples, Stations
from pipeline.well import attach, attached

TAKEN_BY = {
    "samples": "raw samples are read by read_samples, as in pipelines/point-gyro.yaml and "
    "pipelines/continuous-gyro.yaml",
    "stations": "survey stations are read by read_stations, as in pipelines/survey.yaml",
    "readings": "position readings are read by read_readings, as in "
    "pipelines/point-gyro-readings.yaml",
}
"""The kind a file of another kind holds → the stage and shipped pipelines that take it."""


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
    reads: ClassVar[str] = "stations"
    """the kind of table the stage reads"""
    _option_files: list[tuple[str, Path]] = PrivateAttr(default_factory=list)

    def parameter_files(self) -> list[tuple[str, Path]]:
        """The files the reader options name (``options.profile``), found when the
        pipeline was validated with its registry (:mod:`pipeline.inputfiles`)."""
        return self._option_files

    @model_validator(mode="wrap")
    @classmethod
    def _options_fit_the_reader(
        cls, data: Any, handler: ModelWrapValidatorHandler[ReadParams], info: ValidationInfo
    ) -> ReadParams:
        """With the registry in the validation context (when a pipeline is validated), the
        options are validated by the reader's own options model, each problem located at its
        option."""
        params = handler(data)
        registry = (info.context or {}).get("registry")
        if isinstance(registry, Registry):
            try:
                parsed = registry.check_reader_options(cls.reads, params.reader, params.options)
                if parsed is not None:
                    params._option_files = list(parameter_paths(parsed, "options."))
            except ValidationError as exc:
                raise ValidationError.from_exception_data(
                    cls.__name__,
                    [
                        InitErrorDetails(
                            type=e["type"],
                            loc=("options", *e["loc"]),
                            input=e["input"],
                            ctx=e.get("ctx", {}),
                        )
                        for e in exc.errors()
                    ],
                ) from None
        return params


class WriteParams(BaseModel):
    """Parameters of the write stage."""

    model_config = ConfigDict(extra="forbid")
    writer: Annotated[str, registered("writer")] = Field(
        description="writer name (csv, parquet, …)"
    )
    filename: OutputFilename | None = Field(
        None, description="output file name; default '<stage id>.<writer extension>'"
    )

    def output_path(self, ctx: StageContext, extension: str) -> Path:
        """Where the stage writes: ``filename``, or ``<stage id>.<extension>``."""
        return ctx.output_path(self.filename or f"{ctx.stage_id}.{extension}")

    def output_names(self, stage_id: str, registry: Registry) -> list[str]:
        """The file the stage writes (checked by the planner against the other stages')."""
        return [self.filename or f"{stage_id}.{registry.writers[self.writer][0].extension}"]


def read_stage(
    kind: str, *, streamed: bool = False, into_well: bool = True
) -> Callable[[Mapping[str, pa.Table], ReadParams, StageContext], dict[str, Port]]:
    """Stage function reading the pipeline input into a table of ``kind`` (``streamed``: a
    stream of record batches, :meth:`StageContext.read_input_stream`; ``into_well``: the
    file's header states the run's well, as :meth:`StageContext.read_input` takes it)."""

    def read(
        inputs: Mapping[str, pa.Table], params: ReadParams, ctx: StageContext
    ) -> dict[str, Port]:
        reading = ctx.read_input_stream if streamed else ctx.read_input
        try:
            value, header = reading(
                params.input,
                kind,
                reader=params.reader,
                options=params.options,
                into_well=into_well,
            )
        except WrongKindError as exc:
            hint = f"; {TAKEN_BY[exc.found]}" if exc.found in TAKEN_BY else ""
            raise WrongKindError(exc.path, exc.reason + hint, exc.line, found=exc.found) from None
        if isinstance(value, TableStream):
            return {kind: value.replace_schema_metadata(attached(value.schema, header))}
        return {kind: attach(value, header)}

    return read


def read_stage_def(
    name: str,
    kind: str,
    contract: type[TableContract],
    description: str,
    default_input: str,
    *,
    streamed: bool = False,
    into_well: bool = True,
) -> StageDef:
    """A stage reading the pipeline input ``default_input`` (unless told another) into a
    table of ``kind`` on the output port ``kind`` (``streamed``: a streamed port;
    ``into_well``: :func:`read_stage`'s)."""
    params = create_model(
        f"{kind.title().replace('_', '')}ReadParams",
        __base__=ReadParams,
        __doc__=f"Parameters of the {name} stage.",
        input=(str, pipeline_input(default_input, "name of the pipeline input to read")),
    )
    params.reads = kind
    return StageDef(
        name=name,
        func=read_stage(kind, streamed=streamed, into_well=into_well),
        description=description,
        outputs={kind: contract},
        params=params,
        streamed_outputs=frozenset({kind} if streamed else ()),
    )


def write(inputs: Mapping[str, Port], params: WriteParams, ctx: StageContext) -> dict[str, Port]:
    """Write the input table through the chosen writer (published when the run succeeds):
    batch by batch when the writer writes streams."""
    writer = ctx.writer(params.writer)
    path = params.output_path(ctx, writer.extension)
    write_port(writer, inputs["table"], path, ctx.well)
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
        register(
            read_stage_def(name, kind, contract, description, kind, streamed=kind == "samples")
        )
    register(
        StageDef(
            name="write",
            func=write,
            description="Write a table to a file in the output directory with a named writer.",
            inputs={"table": AnyTable},
            params=WriteParams,
            streamed_inputs=frozenset({"table"}),
        )
    )
