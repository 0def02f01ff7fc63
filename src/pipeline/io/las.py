"""Built-in LAS plugin: a reader of LAS 1.2, 2.0 and 3.0 files as survey stations, raw
sensor samples or any well log, and a LAS 2.0 writer of any table's numeric columns.

The reader takes its options from :mod:`pipeline.io.las_options`, splits and decodes the
file and reads its header items (:mod:`pipeline.io.las_header`). For ``stations`` and
``samples`` it chooses the curve of each column of the kind with its unit and north
reference (:mod:`pipeline.io.las_curves`) and reads the values of the ``~A`` rows
(:mod:`pipeline.io.las_rows`), in canonical units; a ``log`` keeps every curve as logged
(:mod:`pipeline.io.las_log`). The well metadata come from :mod:`pipeline.io.las_well`. The
writer is :mod:`pipeline.io.las_write`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.errors import InputFileError
from pipeline.hookspecs import hookimpl
from pipeline.io.conventions import to_canonical
from pipeline.io.las_curves import (
    KINDS,
    azimuth_north,
    choose,
    columns,
    declared_north,
    factor,
    make_table,
    one_north,
)
from pipeline.io.las_header import BOM, SNIFF_BYTES, load, parse_header, require_curves, text_head
from pipeline.io.las_log import read_log
from pipeline.io.las_options import LasOptions
from pipeline.io.las_rows import check_index, check_range, null_values, read_data
from pipeline.io.las_well import well_metadata
from pipeline.io.las_write import write_las
from pipeline.io.sniffing import file_head
from pipeline.registry import ReaderDef, WriterDef
from pipeline.tables import LogTable, RawSamples, Stations
from pipeline.well import WellMetadata

# ---------------------------------------------------------------------------- reader


def read_las(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read a LAS file as ``stations`` (md m, inc/azi deg; tvd/north/east m and dls deg/30m
    when present), ``samples`` (time s, gyros deg/h, accelerometers m/s2, magnetometers
    nT, md m, frame_angle deg) or ``log`` (every curve as logged), plus ``source_line``
    (the file line of each row)."""
    if kind not in (*KINDS, "log"):
        raise ValueError(f"the las reader reads kinds {sorted((*KINDS, 'log'))}, not {kind!r}")
    opts = LasOptions.model_validate(options or {})
    source = load(path)
    header = parse_header(path, source.header)
    if kind == "log":
        return read_log(path, source, header, opts), well_metadata(path, header, None, strict=False)
    spec = KINDS[kind]
    require_curves(path, header)
    if source.title_line == 0:
        raise InputFileError(path, "no ~A (data) section")
    declared = declared_north(path, header)
    chosen = choose(path, header, spec, opts, declared)
    factors = {name: factor(path, header.curves[i], name, opts) for name, i in chosen.items()}
    north, file_north = None, one_north(path, declared)
    if "azi" in chosen:
        north, file_north = azimuth_north(path, header.curves[chosen["azi"]], declared, opts)
    data = read_data(path, source, header, sorted({0, *chosen.values()}))
    nulls = null_values(path, header, opts)
    masks = {i: np.isin(values, nulls) for i, values in data.values.items()}
    check_index(path, header, data, masks, [0, chosen[spec.key]])
    check_range(path, header, data.values[0], data.lines, nulls)
    table = make_table(spec, columns(path, spec, header, chosen, data, masks, factors), north)
    if kind == "samples":
        try:
            table = to_canonical(table, opts.conventions)
        except ValueError as exc:
            raise InputFileError(path, f"option conventions: {exc}") from None
    return table, well_metadata(path, header, file_north)


def sniff(path: Path) -> bool:
    """By content: the first line that is neither blank nor a ``#`` comment opens ``~V``
    (in UTF-8, Windows-1252 or UTF-16 text)."""
    head = file_head(path, SNIFF_BYTES)
    if head is None:
        return False
    for line in text_head(head).removeprefix(BOM).splitlines():
        text = line.strip()
        if text and not text.startswith(b"#"):
            return text[:2].upper() == b"~V"
    return False


# ---------------------------------------------------------------------------- hooks


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="las",
            description="LAS 1.2/2.0/3.0 files: survey stations, raw sensor samples or any "
            "well log",
            kinds={"stations": Stations, "samples": RawSamples, "log": LogTable},
            read=read_las,
            sniff=sniff,
            options=LasOptions,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="las",
            description="numeric columns of any table (a log, stations, samples) as LAS 2.0 "
            "with units, well metadata and north reference",
            extension="las",
            write=write_las,
        )
    )
