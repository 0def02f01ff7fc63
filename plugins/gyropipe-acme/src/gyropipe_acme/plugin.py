"""The gyropipe plugin ``acme`` (entry point ``acme = "gyropipe_acme.plugin"`` in the group
``gyropipe``): a reader and a writer of Acme GyroLog ``.agl`` raw-sample files and a reader of
Acme survey reports (``.txt`` stations), and the Acme tool (error) model ``ACME-GYRO-V2``, a
model file. Like any plugin, it imports gyropipe only from :mod:`pipeline.plugin`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow as pa

from gyropipe_acme import gyrolog, survey_report
from pipeline.plugin import (
    RawSamples,
    ReaderDef,
    Stations,
    ToolModelDef,
    WellMetadata,
    WriterDef,
    hookimpl,
)

MODELS = Path(__file__).parent / "models"


def read(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read an Acme file as canonical RawSamples (``kind`` is always ``samples``, the one
    kind this reader declares; it takes no options)."""
    return gyrolog.read_samples(path)


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="acme",
            description="Acme GyroLog v2 raw samples (.agl), converted from Acme's units and axes",
            kinds={"samples": RawSamples},
            read=read,
            sniff=gyrolog.sniff,
        )
    )
    register(
        ReaderDef(
            name="acme_survey",
            description="Acme survey report stations (.txt), depths in feet",
            kinds={"stations": Stations},
            read=lambda path, kind, options: survey_report.read_stations(path, options),
            sniff=survey_report.sniff,
            options=survey_report.SurveyReportOptions,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="acme",
            description="Acme GyroLog v2 raw samples, in Acme's units and axes",
            extension="agl",
            write=gyrolog.write_samples,
        )
    )


@hookimpl
def gyropipe_register_tool_models(register: Callable[[ToolModelDef], None]) -> None:
    register(
        ToolModelDef(
            name="ACME-GYRO-V2",
            path=MODELS / "acme-gyro-v2.yaml",
            description="Acme GyroLog v2: OWSG GYRO-NS with Acme's gyro noise and thermal term",
        )
    )
