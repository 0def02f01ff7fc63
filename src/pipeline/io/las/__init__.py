"""Built-in LAS plugin: a reader of LAS 1.2, 2.0 and 3.0 files as survey stations, raw
sensor samples or any well log, and a LAS 2.0 writer of any table's numeric columns.

The reader takes its options from :mod:`pipeline.io.las.options`, splits and decodes the
file and reads its header items (:mod:`pipeline.io.las.header`). For ``stations`` and
``samples`` it chooses the curve of each column of the kind with its unit and north
reference (:mod:`pipeline.io.las.curves`) and reads the values of the ``~A`` rows
(:mod:`pipeline.io.las.rows`), in canonical units; a ``log`` keeps every curve as logged
(:mod:`pipeline.io.las.log`). The well metadata come from :mod:`pipeline.io.las.well`. The
writer is :mod:`pipeline.io.las.write`.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.errors import InputFileError
from pipeline.hookspecs import hookimpl
from pipeline.io.conventions import to_canonical
from pipeline.io.las.curves import (
    KINDS,
    azimuth_north,
    choose,
    columns,
    declared_north,
    factor,
    make_table,
    one_north,
)
from pipeline.io.las.header import (
    BOM,
    SNIFF_BYTES,
    Header,
    Source,
    load,
    parse_header,
    require_curves,
    text_head,
)
from pipeline.io.las.log import read_log
from pipeline.io.las.options import LasOptions
from pipeline.io.las.rows import (
    Data,
    IndexRange,
    Mask,
    check_index,
    data_blocks,
    null_mask,
    null_values,
)
from pipeline.io.las.tieon import read_tie_on
from pipeline.io.las.well import well_metadata
from pipeline.io.las.write import write_las
from pipeline.io.mnemonics import CURVES
from pipeline.io.nulls import ANGLE_NULL_MARKERS
from pipeline.io.sniffing import file_head
from pipeline.io.uncertainty_columns import Stated, readable, stating
from pipeline.registry import ReaderDef, WriterDef
from pipeline.streams import TableStream
from pipeline.tables import LogTable, RawSamples, Stations
from pipeline.well import WellMetadata

# ---------------------------------------------------------------------------- reader


def read_las(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read a LAS file as ``stations`` (md m, inc/azi deg; tvd/north/east m, dls deg/30m
    and the uncertainty curves gyropipe writes, stating CONF, ERRMODEL and the tie-on
    items, :mod:`pipeline.io.las.tieon`, when present),
    ``samples`` (time s, gyros deg/h, accelerometers m/s2, magnetometers nT, md m,
    frame_angle deg) or ``log`` (every curve as logged), plus ``source_line``
    (the file line of each row)."""
    rows, well = _open(path, kind, options)
    if isinstance(rows, pa.Table):
        return rows, well
    return pa.concat_tables(list(rows.tables()), promote_options="none"), well


def stream_las(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
    """:func:`read_las` as a stream of record batches, a block of rows (about
    :data:`~pipeline.io.las.fast.BLOCK` bytes of the ``~A`` section) at a time, checked
    as they pass (a log is read whole, then cut)."""
    rows, well = _open(path, kind, options)
    if isinstance(rows, pa.Table):
        return TableStream.from_table(rows), well
    return TableStream.of_batches(rows.schema, rows.batches), well


@dataclass(frozen=True)
class _Rows:
    """What a stations or samples read needs besides the rows: their table a block at a
    time (:meth:`tables`)."""

    path: Path
    kind: str
    source: Source
    header: Header
    chosen: dict[str, int]
    factors: dict[str, float]
    north: str | None
    opts: LasOptions
    stated: Stated
    """what CONF, ERRMODEL and the tie-on items state of the uncertainty curves"""

    @property
    def schema(self) -> pa.Schema:
        """The tables' schema (that of a table without rows)."""
        empty = Data({i: np.empty(0) for i in self._wanted()}, np.empty(0, np.int64))
        masks = {i: np.zeros(0, bool) for i in self._wanted()}
        return self._table(empty, masks).schema

    def tables(self) -> Iterator[pa.Table]:
        """The table of each block of rows, checked (nulls in the index and the key
        column, STRT/STOP/STEP), in canonical units."""
        path, header, spec = self.path, self.header, KINDS[self.kind]
        nulls = null_values(path, header, self.opts)
        angle_nulls = nulls + [m for m in ANGLE_NULL_MARKERS if m not in nulls]
        angles = {
            i
            for name, i in self.chosen.items()
            if name in CURVES and CURVES[name].quantity in ("angle", "dogleg_severity")
        }
        index = IndexRange(path, header, nulls)
        for data in data_blocks(path, self.source, header, self._wanted()):
            if data.lines.size == 0:
                continue
            masks = {
                i: null_mask(values, angle_nulls if i in angles else nulls, data.ranges.get(i))
                for i, values in data.values.items()
            }
            check_index(path, header, data, masks, [0, self.chosen[spec.key]])
            index.feed(data.values[0], data.lines)
            yield self._table(data, masks)
        index.finish()

    def batches(self) -> Iterator[pa.RecordBatch]:
        for table in self.tables():
            yield from table.to_batches()

    def _wanted(self) -> list[int]:
        return sorted({0, *self.chosen.values()})

    def _table(self, data: Data, masks: dict[int, Mask]) -> pa.Table:
        spec = KINDS[self.kind]
        cols = columns(self.path, spec, self.header, self.chosen, data, masks, self.factors)
        table = stating(make_table(spec, cols, self.north), self.stated)
        if self.kind != "samples":
            return table
        try:
            return to_canonical(table, self.opts.conventions)
        except ValueError as exc:
            raise InputFileError(self.path, f"option conventions: {exc}") from None


def _open(path: Path, kind: str, options: Any) -> tuple[pa.Table | _Rows, WellMetadata]:
    """The header read and the curves chosen: a log's whole table, or what reads the rows
    of stations or samples; and the well metadata."""
    if kind not in (*KINDS, "log"):
        raise ValueError(f"the las reader reads kinds {sorted((*KINDS, 'log'))}, not {kind!r}")
    opts: LasOptions = options or LasOptions()
    source = load(path)
    header = parse_header(path, source.header, source.data_set)
    if kind == "log":
        return read_log(path, source, header, opts), well_metadata(path, header, None, strict=False)
    spec = KINDS[kind]
    require_curves(path, header)
    declared = declared_north(path, header)
    stated = _stated(path, header)
    chosen = choose(path, header, spec, opts, declared)
    chosen = readable(
        path, chosen, stated, {name: header.curves[i].line for name, i in chosen.items()}
    )
    if source.title_line == 0:  # after the curves: a log's header alone reads as a log
        raise InputFileError(path, "no ~A (data) section")
    factors = {name: factor(path, header.curves[i], name, opts) for name, i in chosen.items()}
    north, file_north = None, one_north(path, declared)
    if "azi" in chosen:
        north, file_north = azimuth_north(path, header.curves[chosen["azi"]], declared, opts)
    rows = _Rows(path, kind, source, header, chosen, factors, north, opts, stated)
    rows.schema  # noqa: B018  (a conventions option that cannot apply fails before the rows)
    return rows, well_metadata(path, header, file_north, depth_unit=opts.units.get("md"))


def _stated(path: Path, header: Header) -> Stated:
    """What the header's CONF, ERRMODEL and TIE… items state of the uncertainty curves."""
    items = {name: header.find(path, name) for name in ("CONF", "ERRMODEL")}
    conf, model = ((i.value, i.line) if i is not None else None for i in items.values())
    return replace(Stated.of(path, conf, model), tie_on=read_tie_on(path, header))


_TITLES = (b"~V", b"~W", b"~C", b"~A")
"""Sections a LAS file may open with: ``~V``, or ``~W``/``~C``/``~A`` in a minimal file
(lasio's ``barebones.las`` opens with ``~C``, ``barebones2.las`` with ``~A``)."""


def sniff(path: Path) -> bool:
    """By content: the first line that is neither blank nor a ``#`` comment opens ``~V``,
    ``~W``, ``~C`` or ``~A`` (in UTF-8, Windows-1252 or UTF-16 text)."""
    head = file_head(path, SNIFF_BYTES)
    if head is None:
        return False
    for line in _LINES.finditer(text_head(head).removeprefix(BOM)):
        text = line[0].strip()
        if text and not text.startswith(b"#"):
            return text[:2].upper() in _TITLES
    return False


_LINES = re.compile(rb"[^\r\n]+")
"""A line of a head that is not empty, found one at a time: a binary file's 64 KiB split
into lines whole cost more than the rest of its sniffing (its first line decides)."""


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
            stream=stream_las,
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
