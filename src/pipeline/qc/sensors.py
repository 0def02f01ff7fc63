"""The sensor means a check sees, and the σ of each: from position readings (magnetometers
averaged from the raw samples each reading came from).

PositionReadings carry no magnetometers: :func:`readings_sensors` averages them from the raw
samples over the span of each reading (its ``n`` samples around ``t``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.earth.frames import FloatArray
from pipeline.qc.options import QcInputError


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


def readings_sensors(readings: pa.Table, samples: pa.Table | None = None) -> Sensors:
    """Sensor means and σ of PositionReadings rows; magnetometers averaged from the raw
    ``samples`` over each reading's span (see :func:`magnetic_means`) when given."""
    n = float_column(readings, "n")

    def triad(prefix: str) -> tuple[FloatArray, FloatArray]:
        mean = np.stack([float_column(readings, f"{prefix}_{a}") for a in "xyz"], axis=-1)
        std = np.stack([float_column(readings, f"{prefix}_{a}_std") for a in "xyz"], axis=-1)
        return mean, std / np.sqrt(n)[:, None]

    gyro, gyro_sigma = triad("gyro")
    acc, acc_sigma = triad("acc")
    mag = mag_sigma = None
    if samples is not None and all(has_data(samples, f"mag_{a}") for a in "xyz"):
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
    if readings.num_rows and not {"n", "duration"} <= set(readings.column_names):
        raise QcInputError(
            "the readings carry no n/duration columns: cannot find the samples each one "
            "averaged, so the magnetometers cannot be checked"
        )
    n = float_column(readings, "n").astype(int)
    rate = n / float_column(readings, "duration")
    half = (n - 1) / (2 * rate) + 0.25 / rate
    t = float_column(readings, "t")
    time = samples.column("time").to_numpy()
    lo = np.searchsorted(time, t - half)
    hi = np.searchsorted(time, t + half, side="right")
    bad = np.flatnonzero(hi - lo != n)
    if bad.size:
        i = int(bad[0])
        raise QcInputError(
            f"reading at t = {t[i]:g} s averaged {n[i]} samples but the samples hold "
            f"{hi[i] - lo[i]} in its span: are these the samples the readings came from?"
        )
    mag = np.stack([float_column(samples, f"mag_{a}") for a in "xyz"], axis=-1)
    if len(n) == 0:
        return np.empty((0, 3)), np.empty((0, 3))
    index = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    offsets = np.concatenate([[0], np.cumsum(n)[:-1]])
    values = mag[index]
    mean = np.add.reduceat(values, offsets, axis=0) / n[:, None]
    dev = values - np.repeat(mean, n, axis=0)
    std = np.sqrt(np.add.reduceat(dev**2, offsets, axis=0) / np.maximum(n - 1, 1)[:, None])
    return mean, std / np.sqrt(n)[:, None]
