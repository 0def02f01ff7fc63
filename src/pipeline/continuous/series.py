"""The integrated run kept on disk (:class:`StoredRun`), read back by sample range with the
closure and the run-wide flags applied, and its full-rate series as a stream of record
batches (:func:`series_stream`).

Units: times s, angles rad (the series' table: degrees).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.continuous.run import Odometer
from pipeline.continuous.sigma import RunGeometry
from pipeline.continuous.sigma_noise import InclinationNoise
from pipeline.continuous.store import chunks
from pipeline.continuous.tables import (
    FLAG_AFTER_VERTICAL,
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_LARGE_MISALIGNMENT,
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
    ContinuousSeries,
)
from pipeline.earth.frames import FloatArray
from pipeline.streams import TableStream

__all__ = ["RunPart", "StoredRun", "azimuth_degrees", "series_stream"]

_NOT_INTEGRATED = FLAG_NEAR_VERTICAL | FLAG_LARGE_MISALIGNMENT | FLAG_AZIMUTH_UNDEFINED


@dataclass(frozen=True)
class RunPart:
    """Samples of an integrated run: time s, odometer MD m, angles rad, flags ``FLAG_*``."""

    time: FloatArray
    md: FloatArray
    inc: FloatArray
    azi: FloatArray
    """closed azimuth"""
    toolface: FloatArray
    flags: NDArray[np.int64]


@dataclass(frozen=True)
class StoredRun:
    """An integrated run in the odometer's store, run sample 0 at row 0 of the columns
    ``inc``, ``toolface``, ``flags``, ``held`` and the azimuth column ``azi_column`` (before
    closure), all rad; the gyro's misalignment δ from the high side is the toolface (a
    single-axis tool, ``misaligned``) or 0."""

    odometer: Odometer
    latitude: float
    """deg"""
    closure: bool
    """the budget removes the misclosure on the end stop"""
    backward: bool
    """integrated back in time from the end stop (no closure)"""
    inc_noise: InclinationNoise
    azi_column: str
    misclosure: float
    """integrated minus end-stop azimuth before correction, rad (NaN: no closure)"""
    shift: float = 0.0
    """misclosure removed linearly in time as the azimuth is read, rad"""
    misaligned: bool = False
    """δ is the toolface (the servo keeps a single-axis gyro near the high side), else 0"""
    open_end: bool = False
    """the end stop was not compassed: integrated from the start stop, no closure"""
    halves: bool = False
    """the store holds tan(I/2) (column ``inc_half``) and, where misaligned, tan(δ/2)
    (``toolface_half``) as the integration had them"""

    @property
    def size(self) -> int:
        return self.odometer.size

    @property
    def rows(self) -> int:
        return self.odometer.rows

    def times(self, lo: int, hi: int) -> FloatArray:
        """Times of run samples ``lo``…``hi − 1``, s."""
        return self.odometer.time(lo, hi)

    def held_span(self) -> tuple[int, int] | None:
        """First and last sample whose azimuth was held (None: none)."""
        first = last = -1
        for a, b in chunks(0, self.size, self.rows):
            held = np.flatnonzero(self.odometer.store.read("held", a, b))
            if held.size:
                first = a + int(held[0]) if first < 0 else first
                last = a + int(held[-1])
        return None if first < 0 else (first, last)

    def read(self, lo: int, hi: int, held: tuple[int, int] | None) -> RunPart:
        """Time (s), odometer MD (m), inc, closed azimuth, toolface (rad) and flags of run
        samples ``lo``…``hi − 1``; ``held``: :meth:`held_span`."""
        t, inc, azi, flags = self.angles(lo, hi, held)
        return RunPart(
            time=t,
            md=self.odometer.reading(lo, hi),
            inc=inc,
            azi=azi,
            toolface=self.odometer.store.floats("toolface", lo, hi),
            flags=flags,
        )

    def angles(
        self, lo: int, hi: int, held: tuple[int, int] | None
    ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.int64]]:
        """Time (s), inc, closed azimuth (rad) and flags of run samples ``lo``…``hi − 1``
        (:meth:`read` less the MD and toolface)."""
        store, t = self.odometer.store, self.odometer.time(lo, hi)
        azi = store.floats(self.azi_column, lo, hi)
        if self.shift:
            t0 = float(self.odometer.time(0, 1)[0])
            t_end = float(self.odometer.time(self.size - 1, self.size)[0])
            azi = azi - self.shift * ((t - t0) / (t_end - t0))
        flags = store.ints("flags", lo, hi)
        if self.backward or self.open_end:
            flags |= FLAG_NO_CLOSURE
        if held is not None:  # integrated after a held section (back in time: before it)
            index = np.arange(lo, hi)
            after = index <= held[1] if self.backward else index >= held[0]
            after &= store.read("held", lo, hi) == 0
            np.bitwise_or(flags, FLAG_AFTER_VERTICAL, out=flags, where=after)
        return t, store.floats("inc", lo, hi), azi, flags

    def slice(self, lo: int, hi: int) -> RunGeometry:
        """Samples ``lo``…``hi − 1`` as the budget reads them (flags without the run-wide
        ones, which do not change what is integrated)."""
        t, inc, azi, flags = self.angles(lo, hi, None)
        store = self.odometer.store
        return RunGeometry(
            time=t,
            inc=inc,
            azi=azi,
            misalignment=(
                store.floats("toolface", lo, hi) if self.misaligned else np.zeros(t.size)
            ),
            inc_half=store.floats("inc_half", lo, hi) if self.halves else None,
            misalignment_half=(
                store.floats("toolface_half", lo, hi) if self.halves and self.misaligned else None
            ),
            usable=(flags & _NOT_INTEGRATED) == 0,
            latitude=self.latitude,
            closure=self.closure,
            backward=self.backward,
            inc_noise=self.inc_noise,
        )


def series_stream(run: StoredRun) -> TableStream:
    """The full-rate series (:class:`ContinuousSeries`, degrees) read from the store a chunk
    at a time on every pass; its ``nbytes`` the bytes a pass decodes to (fixed-width
    columns), so that the runner keeps a pass read by several where it is small."""
    contract = ContinuousSeries.compiled()
    empty = {f.name: pa.array([], type=f.type) for f in contract.schema()}
    schema = contract.make_table(empty, north_reference="true").schema
    held = run.held_span()

    def batches() -> Iterator[pa.RecordBatch]:
        for a, b in chunks(0, run.size, run.rows):
            part = run.read(a, b, held)
            table = contract.make_table(
                {
                    "time": part.time,
                    "md": part.md,
                    "inc": np.degrees(part.inc),
                    "azi": azimuth_degrees(part.azi),
                    "toolface": np.degrees(part.toolface),
                    "flags": part.flags,
                },
                north_reference="true",
            )
            yield from table.to_batches()

    row_bytes = sum(f.type.byte_width for f in schema)
    return TableStream(schema, batches, nbytes=run.size * row_bytes)


def azimuth_degrees(azi: FloatArray) -> FloatArray:
    """Azimuths (rad, any turn) in degrees in [0, 360): ``np.degrees(azi) % 360``, a result
    of 360 (a tiny negative angle rounded) made 0, to the bit; the modulo (≈ 9 ns a value)
    taken only where an angle is not already inside (0, 360) (−0 and 0 go through it too)."""
    deg: FloatArray = np.degrees(azi)
    outside = np.flatnonzero(~((deg > 0.0) & (deg < 360.0)))
    if outside.size:
        turned = deg[outside] % 360.0
        deg[outside] = np.where(turned < 360.0, turned, 0.0)
    return deg
