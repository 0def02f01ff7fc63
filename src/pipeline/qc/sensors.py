"""The sensor means a check sees, and the σ of each: from position readings (magnetometers
averaged from the raw samples each reading came from).

PositionReadings carry no magnetometers: :func:`readings_sensors` averages them from the raw
samples over the span of each reading (its ``n`` samples around ``t``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray
from pipeline.qc.options import QcInputError
from pipeline.streams import TableStream

IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Sensors:
    """Mean readings at rest and the σ of each mean (std/√n; NaN when unknown). Gyro axes a
    tool lacks are NaN. Gyros °/h, accelerometers m/s², magnetometers nT, shape (R, 3)."""

    gyro: FloatArray
    gyro_sigma: FloatArray
    acc: FloatArray
    acc_sigma: FloatArray
    mag: FloatArray | None
    mag_sigma: FloatArray | None
    gyro_axes: str
    """gyro axes the tool has ("x", "xy" or "xyz")"""


def float_column(table: pa.Table, name: str) -> FloatArray:
    """A float column as an array (NaN where null or absent)."""
    if name not in table.column_names:
        return np.full(table.num_rows, np.nan)
    values: FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


def readings_sensors(readings: pa.Table, samples: pa.Table | TableStream | None = None) -> Sensors:
    """Sensor means and σ of PositionReadings rows; magnetometers averaged from the raw
    ``samples`` over each reading's span (see :func:`magnetic_means`) when given — a stream
    of them in one pass (:func:`stream_magnetic_means`)."""
    n = float_column(readings, "n")

    def triad(prefix: str) -> tuple[FloatArray, FloatArray]:
        mean = np.stack([float_column(readings, f"{prefix}_{a}") for a in "xyz"], axis=-1)
        std = np.stack([float_column(readings, f"{prefix}_{a}_std") for a in "xyz"], axis=-1)
        return mean, std / np.sqrt(n)[:, None]

    gyro, gyro_sigma = triad("gyro")
    acc, acc_sigma = triad("acc")
    mag = mag_sigma = None
    if isinstance(samples, TableStream):
        mag, mag_sigma = stream_magnetic_means(readings, samples)
    elif samples is not None and all(has_data(samples, f"mag_{a}") for a in "xyz"):
        mag, mag_sigma = magnetic_means(readings, samples)
    return Sensors(gyro, gyro_sigma, acc, acc_sigma, mag, mag_sigma, gyro_axes(readings))


def has_data(table: pa.Table, name: str) -> bool:
    """Whether ``table`` has a column ``name`` with any data."""
    return name in table.column_names and table.column(name).null_count < table.num_rows


def gyro_axes(table: pa.Table) -> str:
    """Gyro axes with data in a samples or readings table ("x", "xy", "xyz"…)."""
    return "".join(a for a in "xyz" if has_data(table, f"gyro_{a}"))


def magnetic_means(readings: pa.Table, samples: pa.Table) -> tuple[FloatArray, FloatArray]:
    """Mean magnetometer vector (nT) of each reading and its σ (std/√n), from the raw
    samples the reading averaged: the ``n`` samples centred on its mid-time ``t``
    (``duration`` = n / sample rate). Raises :class:`QcInputError` when the readings carry
    no n/duration or the samples there do not match."""
    n, t, start, stop = spans(readings)
    time = samples.column("time").to_numpy()
    lo = np.searchsorted(time, start)
    hi = np.searchsorted(time, stop, side="right")
    bad = np.flatnonzero(hi - lo != n)
    if bad.size:
        i = int(bad[0])
        raise mismatch(float(t[i]), int(n[i]), int(hi[i] - lo[i]))
    mag = np.stack([float_column(samples, f"mag_{a}") for a in "xyz"], axis=-1)
    if len(n) == 0:
        return np.empty((0, 3)), np.empty((0, 3))
    index = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    return mean_sigma(mag[index], n)


def spans(readings: pa.Table) -> tuple[IntArray, FloatArray, FloatArray, FloatArray]:
    """Each reading's sample count, mid-time and the first and last time (s) of the samples
    it averaged (half a sample of slack each side); :class:`QcInputError` without
    n/duration."""
    if readings.num_rows and not {"n", "duration"} <= set(readings.column_names):
        raise QcInputError(
            "the readings carry no n/duration columns: cannot find the samples each one "
            "averaged, so the magnetometers cannot be checked"
        )
    n = float_column(readings, "n").astype(int)
    rate = n / float_column(readings, "duration")
    half = (n - 1) / (2 * rate) + 0.25 / rate
    t = float_column(readings, "t")
    return n, t, t - half, t + half


def mismatch(t: float, n: int, held: int) -> QcInputError:
    """A reading whose span holds another number of samples than it averaged."""
    return QcInputError(
        f"reading at t = {t:g} s averaged {n} samples but the samples hold "
        f"{held} in its span: are these the samples the readings came from?"
    )


def mean_sigma(values: FloatArray, n: IntArray) -> tuple[FloatArray, FloatArray]:
    """Mean and σ of the mean (std/√n) of consecutive runs of ``n`` rows of ``values``."""
    offsets = np.concatenate([[0], np.cumsum(n)[:-1]])
    mean = np.add.reduceat(values, offsets, axis=0) / n[:, None]
    dev = values - np.repeat(mean, n, axis=0)
    std = np.sqrt(np.add.reduceat(dev**2, offsets, axis=0) / np.maximum(n - 1, 1)[:, None])
    return mean, std / np.sqrt(n)[:, None]


MAGNETOMETERS = tuple(f"mag_{a}" for a in "xyz")


def stream_magnetic_means(
    readings: pa.Table, samples: TableStream
) -> tuple[FloatArray, FloatArray] | tuple[None, None]:
    """:func:`magnetic_means` of a stream of raw samples, in one pass and bounded memory: a
    reading's magnetometer samples are kept until its span has passed, then its mean and σ
    are computed as the whole table gives them. (None, None) when the samples have no
    magnetometer data (a column absent or all null), as :func:`readings_sensors` decides."""
    if not set(MAGNETOMETERS) <= set(samples.schema.names):
        return None, None
    if readings.num_rows and not {"n", "duration"} <= set(readings.column_names):
        rows, nulls = 0, np.zeros(3, dtype=np.int64)
        for batch in samples:
            rows += batch.num_rows
            nulls += [batch.column(name).null_count for name in MAGNETOMETERS]
        if rows and (nulls < rows).all():
            spans(readings)  # raises: no n/duration to find the samples each one averaged
        return None, None
    n, t, start, stop = spans(readings)
    held = np.zeros(readings.num_rows, dtype=np.int64)
    pieces: dict[int, list[FloatArray]] = {}
    mean, sigma = np.full((readings.num_rows, 3), np.nan), np.full((readings.num_rows, 3), np.nan)
    order = np.argsort(stop)
    done, rows, nulls = 0, 0, np.zeros(3, dtype=np.int64)
    for batch in samples:
        rows += batch.num_rows
        nulls += [batch.column(name).null_count for name in MAGNETOMETERS]
        if batch.num_rows == 0:
            continue
        time = batch.column("time").to_numpy()
        mag = np.stack([batch.column(m).to_numpy(zero_copy_only=False) for m in MAGNETOMETERS], -1)
        lo, hi = np.searchsorted(time, start), np.searchsorted(time, stop, side="right")
        for k in np.flatnonzero(hi > lo):
            held[k] += hi[k] - lo[k]
            pieces.setdefault(int(k), []).append(mag[lo[k] : hi[k]].astype(float))
        passed: int = max(done, int(np.searchsorted(stop[order], time[-1])))  # stop < last
        _settle(order[done:passed], n, held, pieces, mean, sigma)
        done = passed
    if rows == 0 or (nulls == rows).any():
        return None, None
    _settle(order[done:], n, held, pieces, mean, sigma)
    bad = np.flatnonzero(held != n)
    if bad.size:
        i = int(bad[0])
        raise mismatch(float(t[i]), int(n[i]), int(held[i]))
    return mean, sigma


def _settle(
    group: IntArray,
    n: IntArray,
    held: IntArray,
    pieces: dict[int, list[FloatArray]],
    mean: FloatArray,
    sigma: FloatArray,
) -> None:
    """Mean and σ of the readings ``group`` whose spans have passed (those holding their
    ``n`` samples; the others are reported at the end), their samples let go."""
    whole = np.array([i for i in sorted(group.tolist()) if held[i] == n[i] and n[i] > 0])
    if whole.size:
        values = np.concatenate([v for i in whole for v in pieces[int(i)]])
        mean[whole], sigma[whole] = mean_sigma(values, n[whole])
    for i in group.tolist():
        pieces.pop(int(i), None)
