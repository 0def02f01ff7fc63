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
(σ = std/√n) and compared with the reference field. Failed windows merged along time are
the magnetic anomaly intervals (:func:`anomaly_intervals`). While the tool accelerates the
per-sample dip carries a/g of error; at logging speeds the window mean rides over it.

Overlapping windows (step < window) repeat evaluations of the same samples: count failures
per interval, not per row. Windows carry no station: ``drop`` policies only mark rows;
``stop`` raises :class:`~pipeline.qc.checks.QcStop` naming the window's times.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from numpy.lib.stride_tricks import sliding_window_view

from pipeline.earth.frames import FloatArray
from pipeline.earth.site import Site
from pipeline.qc.checks import (
    DEFAULTS,
    VECTOR_CHECKS,
    BoolArray,
    Keys,
    QcInputError,
    QcOptions,
    Rows,
    Sensors,
    earth_reference,
    gyro_axes,
    isolate_rows,
    judge,
    limit_rows,
    raise_on_stop,
    results_table,
    vector_checks,
)
from pipeline.qc.tables import MagneticAnomalies
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


def _triad(samples: pa.Table, prefix: str) -> FloatArray | None:
    """(n, 3) columns of a triad, NaN for absent axes; None when no axis is present."""
    names = [f"{prefix}_{a}" for a in "xyz"]
    if not any(n in samples.column_names for n in names):
        return None
    return np.stack(
        [
            samples.column(n).to_numpy(zero_copy_only=False).astype(float)
            if n in samples.column_names
            else np.full(samples.num_rows, np.nan)
            for n in names
        ],
        axis=-1,
    )


def stationary(
    samples: pa.Table, options: QcOptions = DEFAULTS
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Window start and end times (s) and whether each window is stationary (module
    docstring)."""
    time = samples.column("time").to_numpy()
    win = _Windows(time, options)
    return _stationary(samples, time, win, options)


def _stationary(
    samples: pa.Table, time: FloatArray, win: _Windows, options: QcOptions
) -> tuple[FloatArray, FloatArray, BoolArray]:
    gyro = _triad(samples, "gyro")
    acc = _triad(samples, "acc")
    assert gyro is not None and acc is not None  # required by RawSamples
    present = ~np.isnan(gyro).all(axis=0)
    _, gyro_std = win.mean_std(gyro[:, present])
    _, acc_std = win.mean_std(acc)
    still = (gyro_std.max(axis=1) <= options.rest_gyro.limit) & (
        acc_std.max(axis=1) <= options.rest_acc.limit
    )
    md = _md(samples)
    if md is not None:
        t = win.view(time)
        tc = t - t.mean(axis=1, keepdims=True)
        m = win.view(md)
        speed = np.sum(tc * (m - m.mean(axis=1, keepdims=True)), axis=1) / np.sum(tc * tc, axis=1)
        still &= np.abs(speed) <= options.rest_speed
    return time[win.starts], time[win.starts + win.length - 1], still


def _md(samples: pa.Table) -> FloatArray | None:
    if "md" not in samples.column_names or samples.column("md").null_count == samples.num_rows:
        return None
    col = samples.column("md")
    if col.null_count:
        raise QcInputError(f"column 'md' has {col.null_count} missing values: give all or none")
    values: FloatArray = col.to_numpy()
    return values


def window_checks(samples: pa.Table, site: Site, options: QcOptions = DEFAULTS) -> pa.Table:
    """Check continuous raw samples (RawSamples) window by window (module docstring).
    Returns QcResults rows with window times (station and position null, md the window's
    median MD). Raises :class:`~pipeline.qc.checks.QcStop` when a check with policy
    ``stop`` fails, :class:`~pipeline.qc.checks.QcInputError` for data shorter than a
    window."""
    RawSamples.validate_table(samples)
    time = samples.column("time").to_numpy()
    win = _Windows(time, options)
    start, end, still = _stationary(samples, time, win, options)
    count = len(start)
    md = _md(samples)
    md_w = np.median(win.view(md), axis=1) if md is not None else np.full(count, np.nan)
    keys = Keys(np.full(count, -1), np.full(count, -1), md_w, start, end)
    gyro, acc, mag = (_triad(samples, p) for p in ("gyro", "acc", "mag"))
    assert gyro is not None and acc is not None
    earth = earth_reference(site, magnetic=mag is not None, model=options.magnetic_model)

    rest = np.flatnonzero(still)
    gyro_mean, gyro_std = win.mean_std(gyro)
    acc_mean, acc_std = win.mean_std(acc)
    root_n = np.sqrt(win.length)
    sensors = Sensors(
        gyro_mean[rest],
        gyro_std[rest] / root_n,
        acc_mean[rest],
        acc_std[rest] / root_n,
        None,
        None,
        gyro_axes(samples),
    )
    rows = vector_checks(sensors, earth, options, keys.take(rest))
    isolate_rows(rows, np.arange(len(rest)), sensors, earth, options)

    moving = np.flatnonzero(~still)
    moving_keys = keys.take(moving)
    rate = np.sqrt(np.nansum(gyro**2, axis=1)) / DEG_S
    rows += [
        limit_rows(
            "motion_rate",
            "deg/s",
            "|ω|",
            win.largest(rate)[moving],
            options.motion_rate,
            moving_keys,
        ),
        limit_rows(
            "motion_accel",
            "m/s2",
            "||a| − g₀|",
            win.largest(np.abs(np.linalg.norm(acc, axis=1) - earth.gravity))[moving],
            options.motion_accel,
            moving_keys,
        ),
        limit_rows(
            "gyro_saturation",
            "deg/s",
            "|gyro axis|",
            win.largest(np.nanmax(np.abs(gyro), axis=1) / DEG_S)[moving],
            options.gyro_saturation,
            moving_keys,
        ),
        limit_rows(
            "acc_saturation",
            "m/s2",
            "|accelerometer axis|",
            win.largest(np.abs(acc).max(axis=1))[moving],
            options.acc_saturation,
            moving_keys,
        ),
    ]
    if mag is not None and earth.magnetic is not None:
        rows += _magnetic(
            win, mag, acc, earth.magnetic.total_field, earth.magnetic.dip, options, keys
        )
    qc = results_table(rows)
    raise_on_stop(qc, options)
    return qc


def _magnetic(
    win: _Windows,
    mag: FloatArray,
    acc: FloatArray,
    field: float,
    dip: float,
    options: QcOptions,
    keys: Keys,
) -> list[Rows]:
    """magnetic_field and magnetic_dip from per-sample invariants averaged per window."""
    out = []
    per_sample = {
        "magnetic_field": VECTOR_CHECKS["magnetic_field"].func(mag),
        "magnetic_dip": VECTOR_CHECKS["magnetic_dip"].func(mag, acc),
    }
    for name, reference in (("magnetic_field", field), ("magnetic_dip", dip)):
        spec = VECTOR_CHECKS[name]
        mean, std = win.mean_std(per_sample[name][:, None])
        out.append(
            judge(
                name,
                spec.unit,
                spec.symbol,
                mean[:, 0],
                std[:, 0] / np.sqrt(win.length),
                np.zeros(len(mean), bool),
                np.full(len(mean), reference),
                getattr(options, name),
                keys,
            )
        )
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
