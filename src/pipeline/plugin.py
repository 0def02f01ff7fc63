"""What a gyropipe plugin needs, in one module: ``from pipeline.plugin import …``.

A plugin (a vendor adapter, a stage, a writer, a QC check) imports gyropipe only from here
and from :mod:`pipeline`; everything else in the package is internal and may move. The names
below are re-exported from their home modules unchanged (``pipeline.plugin.Stations is
pipeline.tables.Stations``), so a plugin built on this module keeps working when the inside
is reorganised. How to write one: ``docs/vendor-adapter.md``; a worked example:
``plugins/gyropipe-acme``.

A reader plugin, whole (entry point ``foo = "foo_gyro.plugin"`` in the group ``gyropipe``)::

    from pipeline.plugin import Claim, InputFileError, ReaderDef, Stations, WellMetadata, hookimpl

    def sniff(path):
        '''By content: the first line is ``FOO SURVEY``.'''
        with path.open("rb") as fh:
            return Claim.CONTENT if fh.readline().strip() == b"FOO SURVEY" else Claim.NO

    def read(path, kind, options):
        lines = path.read_text(encoding="utf-8").splitlines()
        rows = [[float(cell) for cell in line.split()] for line in lines[1:] if line.strip()]
        if not rows or any(len(row) != 3 for row in rows):
            raise InputFileError(path, "expected lines of three numbers: md inc azi", line=2)
        md, inc, azi = zip(*rows, strict=True)
        data = {"md": md, "inc": inc, "azi": azi}
        return Stations.compiled().make_table(data, north_reference="true"), WellMetadata()

    @hookimpl
    def gyropipe_register_readers(register):
        register(ReaderDef(name="foo", description="FOO survey stations (.foo)",
                           kinds={"stations": Stations}, read=read, sniff=sniff))

What is here:

- registering: :data:`hookimpl` and the records :class:`StageDef`, :class:`ReaderDef`
  (its ``sniff`` returns a :class:`Claim`), :class:`WriterDef`, :class:`CheckDef`,
  :class:`ToolModelDef` (an error-model file, ``docs/tool-models.md``), :class:`ReportDef`
  (what a stage states in the report's Method table, a section a plugin adds: a
  :class:`ReportSection` of paragraphs, :class:`ReportTable` tables and a
  :class:`ReportFigure` of :class:`ReportLine` series; a :class:`MethodNote`; both given
  a :class:`ReportContext`, and the method a run's :class:`StageSetup`); params
  helpers :class:`NoParams`, :func:`pipeline_input`, :func:`registered`, :data:`InputPath`
  (a parameter naming a file to read: checked by ``validate``, hashed into ``run.json``);
  what a stage is given, :class:`StageContext` (``record_file`` declares a file it finds
  while it runs) and :class:`Provenance`; :class:`TableStream`, what a
  streamed port carries (a schema and record batches: ``StageDef.streamed_inputs`` /
  ``streamed_outputs``, ``ReaderDef.stream``, ``WriterDef.write_stream``);
- batch executors: :class:`ExecutorDef` (``gyropipe batch --executor NAME``), whose factory
  is given an :class:`ExecutorSetup` (workers, the batch's :class:`PipelineRef`, a scheduler
  address) and runs :func:`run_well` on each :class:`WellTask`, handing back its
  :class:`WellOutcome` (``docs/batch.md``, "Executors");
- tables: :class:`TableContract` and :func:`column`, the standard contracts
  (:class:`Stations`, :class:`RawSamples`, :class:`PositionReadings`, :class:`Trajectory`,
  :class:`CheckResults`, :class:`AnyTable`…) and the metadata keys :data:`SOURCE_LINE`,
  :data:`UNIT_KEY`, :data:`NORTH_KEY`;
- the well: :class:`WellMetadata`, :data:`Latitude` (the type of every latitude, deg),
  :data:`NorthReference`, :data:`DefaultNorthReference` (a reader option filled from the
  well metadata), :func:`attach`, :func:`well_of`;
- units and conventions, converted once at ingest: :func:`conversion_factor`,
  :func:`canonical_unit`, :func:`is_unit_of`; :class:`Conventions` and :func:`to_canonical`
  (vendor axes and signs of raw samples); the canonical columns :data:`CURVES` (each a
  :class:`Curve` with its quantity), :func:`canonical_name`, :func:`register_alias`;
- errors: :class:`GyropipeError` and the ones a plugin raises or meets
  (:class:`InputFileError` for a malformed file, :class:`UnitError`,
  :class:`ContractViolation`, :class:`MissingSiteError`, :class:`ReaderError`,
  :class:`ReaderChoiceError`, :class:`ReaderOptionsError`).
"""

from __future__ import annotations

from pipeline.batch.worker import WellOutcome, WellTask, run_well
from pipeline.contracts import NORTH_KEY, SOURCE_LINE, UNIT_KEY, TableContract, column
from pipeline.errors import (
    ContractViolation,
    GyropipeError,
    InputFileError,
    MissingSiteError,
    ReaderChoiceError,
    ReaderError,
    ReaderOptionsError,
    UnitError,
)
from pipeline.executing import ExecutorDef, ExecutorSetup, PipelineRef
from pipeline.hookspecs import hookimpl
from pipeline.inputfiles import InputPath
from pipeline.io.conventions import Conventions, to_canonical
from pipeline.io.mnemonics import CURVES, Curve, canonical_name, register_alias
from pipeline.provenance import Provenance, StageSetup
from pipeline.registry import (
    CheckDef,
    Claim,
    NoParams,
    ReaderDef,
    StageContext,
    StageDef,
    ToolModelDef,
    WriterDef,
    pipeline_input,
    registered,
)
from pipeline.reporting import (
    MethodNote,
    ReportContext,
    ReportDef,
    ReportFigure,
    ReportLine,
    ReportSection,
    ReportTable,
)
from pipeline.streams import TableStream
from pipeline.tables import (
    AcceptanceGates,
    AnyTable,
    CheckResults,
    CompassRejects,
    CompassStations,
    ErrorBudget,
    FreeGyroReadings,
    LogTable,
    PositionReadings,
    RawSamples,
    SimTruth,
    Stations,
    Trajectory,
)
from pipeline.units import canonical_unit, conversion_factor, is_unit_of
from pipeline.well import (
    DefaultNorthReference,
    Latitude,
    NorthReference,
    WellMetadata,
    attach,
    well_of,
)

__all__ = [
    "CURVES",
    "NORTH_KEY",
    "SOURCE_LINE",
    "UNIT_KEY",
    "AcceptanceGates",
    "AnyTable",
    "CheckDef",
    "CheckResults",
    "Claim",
    "CompassRejects",
    "CompassStations",
    "ContractViolation",
    "Conventions",
    "Curve",
    "DefaultNorthReference",
    "ErrorBudget",
    "ExecutorDef",
    "ExecutorSetup",
    "FreeGyroReadings",
    "GyropipeError",
    "InputFileError",
    "InputPath",
    "Latitude",
    "LogTable",
    "MethodNote",
    "MissingSiteError",
    "NoParams",
    "NorthReference",
    "PipelineRef",
    "PositionReadings",
    "Provenance",
    "RawSamples",
    "ReaderChoiceError",
    "ReaderDef",
    "ReaderError",
    "ReaderOptionsError",
    "ReportContext",
    "ReportDef",
    "ReportFigure",
    "ReportLine",
    "ReportSection",
    "ReportTable",
    "SimTruth",
    "StageContext",
    "StageDef",
    "StageSetup",
    "Stations",
    "TableContract",
    "TableStream",
    "ToolModelDef",
    "Trajectory",
    "UnitError",
    "WellMetadata",
    "WellOutcome",
    "WellTask",
    "WriterDef",
    "attach",
    "canonical_name",
    "canonical_unit",
    "column",
    "conversion_factor",
    "hookimpl",
    "is_unit_of",
    "pipeline_input",
    "register_alias",
    "registered",
    "run_well",
    "to_canonical",
    "well_of",
]
