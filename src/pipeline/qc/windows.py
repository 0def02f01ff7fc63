"""Validity checks of continuous data on sliding windows of raw samples (DOMAIN.md §3).

Windows of ``options.window`` seconds start every ``options.step`` seconds (counted in
samples at the mean sample rate). Each window is either

- *stationary*: every gyro axis's sample std ≤ ``rest_gyro`` (°/h), every accelerometer
  axis's ≤ ``rest_acc`` (m/s²) and, with an MD column, the least-squares MD speed
  ≤ ``rest_speed`` (m/s). Only there do the checks at rest run, on the window means
  (σ = std/√n), with fault isolation on the window as a single position; or
- *moving*: the motion bounds are checked on every sample of the window — ``motion_rate``
  (|ω| over the gyro axes present, deg/s), ``motion_accel`` (||a| − g₀|, m/s²) and the
  sensor ranges ``gyro_saturation`` (deg/s) and ``acc_saturation`` (m/s²), largest |axis|.

The magnetic checks run on every window, moving or not: per sample |B| and the dip
``asin(B·d/|B|)`` (d = g/|g|) are rotation-invariant, so they are averaged over the window
(σ = std/√n) and compared with the reference field. An acceleration a of the tool tilts the
measured gravity by up to a/g rad, so the dip is checked only in windows whose MD
acceleration (least-squares quadratic in time) is below ``steady_accel`` — or, without an
MD column, in stationary windows. Failed windows merged along time are the magnetic anomaly
intervals (:func:`anomaly_intervals`).

Overlapping windows (step < window) repeat evaluations of the same samples: count failures
per interval, not per row. Windows carry no station: ``drop`` policies only mark rows;
``stop`` raises :class:`~pipeline.qc.options.QcStop` naming the window's times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from numpy.lib.stride_tricks import sliding_window_view

from pipeline.earth.frames import FloatArray
from pipeline.earth.site import MagneticReference, Site
from pipeline.qc.engine import isolate_rows, raise_on_stop, results_table
from pipeline.qc.options import DEFAULTS, QcInputError, QcOptions
from pipeline.qc.reference import earth_reference
from pipeline.qc.sensors import Sensors, gyro_axes, has_data
from pipeline.qc.tables import MagneticAnomalies
from pipeline.qc.vector_checks import (
    VECTOR_CHECKS,
    BoolArray,
    IntArray,
    Keys,
    Rows,
    judge,
    limit_rows,
    vector_checks,
)
from pipeline.tables import RawSamples

DEG_S = 3600.0
"""°/h per deg/s."""


class _Windows:
    """Sliding windows over the samples: per-window statistics of sample columns."""

    def __init__(self, time: FloatArray, options: QcOptions) -> None:
        n = len(time)
        if n < 2 or time[-1] <= time[0]:
            raise QcInputError(f"need at least 2 samples spanning some time, got {n}")
        rate = (n - 1) / (time[-1] - time[0])
        self.length = max(2, round(options.window * rate))
        if n < self.length:
            raise QcInputError(
                f"{n} samples ({time[-1] - time[0]:g} s) are shorter than one window "
                f"({options.window:g} s): lower the window option"
            )
        self.step = max(1, round(options.step * rate))
        self.starts = np.arange(0, n - self.length + 1, self.step)

    def view(self, x: FloatArray) -> FloatArray:
        """(W, L) view of a per-sample column."""
        out: FloatArray = sliding_window_view(x, self.length)[:: self.step]
        return out

    def mean_std(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Per-window mean and sample std (ddof 1) of each column of x (n, k): (W, k)."""
        views = [self.view(x[:, j]) for j in range(x.shape[1])]
        mean = np.stack([v.mean(axis=1) for v in views], axis=-1)
        std = np.stack([v.std(axis=1, ddof=1) for v in views], axis=-1)
        return mean, std

    def largest(self, x: FloatArray) -> FloatArray:
        out: FloatArray = self.view(x).max(axis=1)
        return out


@dataclass(frozen=True)
class _Samples:
    """Per-sample columns: time s, gyros °/h and accelerometers m/s² (n, 3; absent gyro
    axes NaN), magnetometers nT (n, 3) and MD m when present."""

    time: FloatArray
    gyro: FloatArray
    acc: FloatArray
    mag: FloatArray | None
    md: FloatArray | None
    gyro_axes: str

    @classmethod
    def read(cls, samples: pa.Table) -> _Samples:
        RawSamples.validate_table(samples)

        def triad(prefix: str) -> FloatArray:
            return np.stack(
                [
                    samples.column(f"{prefix}_{a}").to_numpy(zero_copy_only=False).astype(float)
                    if f"{prefix}_{a}" in samples.column_names
                    else np.full(samples.num_rows, np.nan)
                    for a in "xyz"
                ],
                axis=-1,
            )

        md = None
        if has_data(samples, "md"):
            column = samples.column("md")
            if column.null_count:
                raise QcInputError(
                    f"column 'md' has {column.null_count} missing values: give all or none"
                )
            md = column.to_numpy()
        return cls(
            samples.column("time").to_numpy(),
            triad("gyro"),
            triad("acc"),
            triad("mag") if all(has_data(samples, f"mag_{a}") for a in "xyz") else None,
            md,
            gyro_axes(samples),
        )


@dataclass(frozen=True)
class _Motion:
    """Per window: times (s), mean and sample std of the gyros and accelerometers, the MD
    speed (m/s) and acceleration (m/s²) when there is an MD, and whether it is stationary."""

    start: FloatArray
    end: FloatArray
    gyro: tuple[FloatArray, FloatArray]
    acc: tuple[FloatArray, FloatArray]
    speed: FloatArray | None
    accel: FloatArray | None
    still: BoolArray

    @classmethod
    def of(cls, data: _Samples, win: _Windows, options: QcOptions) -> _Motion:
        gyro, acc = win.mean_std(data.gyro), win.mean_std(data.acc)
        still = (np.nanmax(gyro[1], axis=1) <= options.rest_gyro.limit) & (
            acc[1].max(axis=1) <= options.rest_acc.limit
        )
        speed = accel = None
        if data.md is not None:
            speed, accel = _md_motion(win, data.time, data.md)
            still &= np.abs(speed) <= options.rest_speed
        time = data.time
        return cls(
            time[win.starts], time[win.starts + win.length - 1], gyro, acc, speed, accel, still
        )


def stationary(
    samples: pa.Table, options: QcOptions = DEFAULTS
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Window start and end times (s) and whether each window is stationary (module
    docstring)."""
    data = _Samples.read(samples)
    motion = _Motion.of(data, _Windows(data.time, options), options)
    return motion.start, motion.end, motion.still


def _md_motion(win: _Windows, time: FloatArray, md: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Speed (m/s) at the mid-time and acceleration (m/s²) of each window's MD, from a
    least-squares quadratic in time (odometer noise averages out)."""
    t = win.view(time)
    tc = t - t.mean(axis=1, keepdims=True)
    design = np.stack([np.ones_like(tc), tc, tc * tc], axis=-1)  # (W, L, 3)
    normal = np.einsum("wli,wlj->wij", design, design)
    rhs = np.einsum("wli,wl->wi", design, win.view(md) - md[win.starts][:, None])
    coef = np.linalg.solve(normal, rhs[..., None])[..., 0]
    return coef[:, 1], 2 * coef[:, 2]


def window_checks(samples: pa.Table, site: Site, options: QcOptions = DEFAULTS) -> pa.Table:
    """Check continuous raw samples (RawSamples) window by window (module docstring).
    Returns QcResults rows with window times (station and position null, md the window's
    median MD). Raises :class:`~pipeline.qc.options.QcStop` when a check with policy
    ``stop`` fails, :class:`~pipeline.qc.options.QcInputError` for data shorter than a
    window."""
    data = _Samples.read(samples)
    win = _Windows(data.time, options)
    motion = _Motion.of(data, win, options)
    count = len(motion.start)
    md = np.full(count, np.nan) if data.md is None else np.median(win.view(data.md), axis=1)
    keys = Keys(np.full(count, -1), np.full(count, -1), md, motion.start, motion.end)
    earth = earth_reference(site, magnetic=data.mag is not None, model=options.magnetic_model)

    rest = np.flatnonzero(motion.still)
    root_n = np.sqrt(win.length)
    (gyro_mean, gyro_std), (acc_mean, acc_std) = motion.gyro, motion.acc
    sensors = Sensors(
        gyro_mean[rest],
        gyro_std[rest] / root_n,
        acc_mean[rest],
        acc_std[rest] / root_n,
        None,
        None,
        data.gyro_axes,
    )
    rows = vector_checks(sensors, earth, options, keys.take(rest))
    isolate_rows(rows, np.arange(len(rest)), sensors, earth, options)
    rows += _motion_bounds(data, win, earth.gravity, options, keys, np.flatnonzero(~motion.still))
    if data.mag is not None and earth.magnetic is not None:
        steady = (
            motion.still if motion.accel is None else np.abs(motion.accel) <= options.steady_accel
        )
        rows += _magnetic(win, data.mag, data.acc, earth.magnetic, options, keys, steady)
    qc = results_table(rows)
    raise_on_stop(qc, options)
    return qc


def _motion_bounds(
    data: _Samples, win: _Windows, gravity: float, options: QcOptions, keys: Keys, moving: IntArray
) -> list[Rows]:
    """Largest sample values of the ``moving`` windows (indices) against the motion and
    range limits (gravity: the reference, m/s²)."""
    gyro, acc = data.gyro, data.acc
    largest = {
        "motion_rate": np.sqrt(np.nansum(gyro**2, axis=1)) / DEG_S,
        "motion_accel": np.abs(np.linalg.norm(acc, axis=1) - gravity),
        "gyro_saturation": np.nanmax(np.abs(gyro), axis=1) / DEG_S,
        "acc_saturation": np.abs(acc).max(axis=1),
    }
    what = {
        "motion_rate": ("deg/s", "|ω|"),
        "motion_accel": ("m/s2", "||a| − g₀|"),
        "gyro_saturation": ("deg/s", "|gyro axis|"),
        "acc_saturation": ("m/s2", "|accelerometer axis|"),
    }
    return [
        limit_rows(
            name,
            unit,
            text,
            win.largest(largest[name])[moving],
            getattr(options, name),
            keys.take(moving),
        )
        for name, (unit, text) in what.items()
    ]


def _magnetic(
    win: _Windows,
    mag: FloatArray,
    acc: FloatArray,
    reference: MagneticReference,
    options: QcOptions,
    keys: Keys,
    steady: BoolArray,
) -> list[Rows]:
    """magnetic_field and magnetic_dip from per-sample invariants averaged per window; the
    dip only in ``steady`` windows (the others get rows saying why not)."""
    out = []
    for name, per_sample, value in (
        ("magnetic_field", (mag,), reference.total_field),
        ("magnetic_dip", (mag, acc), reference.dip),
    ):
        spec = VECTOR_CHECKS[name]
        mean, std = win.mean_std(spec.func(*per_sample)[:, None])
        out.append(
            judge(
                name,
                spec.unit,
                spec.symbol,
                mean[:, 0],
                std[:, 0] / np.sqrt(win.length),
                np.zeros(len(mean), bool),
                np.full(len(mean), value),
                getattr(options, name),
                keys,
                spec.note,
            )
        )
    dip = out[1]
    dip.evaluated &= steady
    dip.detail[~steady] = "skipped: the tool accelerates (MD), the measured gravity is tilted"
    return out


def anomaly_intervals(qc: pa.Table) -> pa.Table:
    """MagneticAnomalies from window QcResults: windows whose magnetic_field or
    magnetic_dip check failed, merged while they overlap or touch in time."""
    failed = qc.filter(
        pc.and_(
            pc.is_in(qc.column("check"), pa.array(["magnetic_field", "magnetic_dip"])),
            pc.equal(pc.fill_null(qc.column("passed"), True), False),
        )
    )
    failed = failed.filter(pc.is_valid(failed.column("window_start")))
    start = failed.column("window_start").to_numpy()
    order = np.argsort(start, kind="stable")
    start = start[order]
    end = failed.column("window_end").to_numpy()[order]
    md = failed.column("md").to_numpy(zero_copy_only=False).astype(float)[order]
    error = np.abs(
        failed.column("measured").to_numpy()[order] - failed.column("reference").to_numpy()[order]
    )
    is_field = (failed.column("check").to_numpy(zero_copy_only=False) == "magnetic_field")[order]
    reach = np.maximum.accumulate(end) if len(end) else end
    new = np.r_[True, start[1:] > reach[:-1]] if len(start) else np.zeros(0, bool)
    group = np.cumsum(new) - 1
    columns: dict[str, list[object]] = {n: [] for n in MagneticAnomalies.model_fields}
    for g in range(int(group.max()) + 1 if len(group) else 0):
        at = group == g
        known = md[at][~np.isnan(md[at])]
        columns["start"].append(float(start[at].min()))
        columns["end"].append(float(end[at].max()))
        columns["md_from"].append(float(known.min()) if known.size else None)
        columns["md_to"].append(float(known.max()) if known.size else None)
        for name, which in (("field_error", at & is_field), ("dip_error", at & ~is_field)):
            columns[name].append(float(error[which].max()) if which.any() else np.nan)
        columns["windows"].append(len(np.unique(start[at])))
    return MagneticAnomalies.compiled().make_table(columns)
