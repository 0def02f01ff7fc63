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
from pipeline.qc.reference import EarthReference, earth_reference
from pipeline.qc.sensors import Sensors, gyro_axes, has_data
from pipeline.qc.tables import MagneticAnomalies, QcResults
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
from pipeline.streams import Port, TableStream, as_stream
from pipeline.tables import RawSamples

DEG_S = 3600.0
"""°/h per deg/s."""


class _Windows:
    """Sliding windows over the samples: per-window statistics of sample columns. The
    windows' ``length`` and ``step`` (samples) come from the whole survey's sample count and
    time span; ``starts`` are the first samples (regularly spaced) of the windows at hand."""

    def __init__(self, length: int, step: int, starts: IntArray) -> None:
        self.length, self.step, self.starts = length, step, starts

    @classmethod
    def of(cls, n: int, first: float, last: float, options: QcOptions) -> _Windows:
        """Every window of ``n`` samples from time ``first`` to ``last`` (s)."""
        if n < 2 or last <= first:
            raise QcInputError(f"need at least 2 samples spanning some time, got {n}")
        rate = (n - 1) / (last - first)
        length = max(2, round(options.window * rate))
        if n < length:
            raise QcInputError(
                f"{n} samples ({last - first:g} s) are shorter than one window "
                f"({options.window:g} s): lower the window option"
            )
        step = max(1, round(options.step * rate))
        return cls(length, step, np.arange(0, n - length + 1, step))

    def shifted(self, base: int, stop: int) -> _Windows:
        """The windows lying within samples ``base``…``stop − 1``, counted from ``base``."""
        inside = self.starts[(self.starts >= base) & (self.starts + self.length <= stop)]
        return _Windows(self.length, self.step, inside - base)

    def view(self, x: FloatArray) -> FloatArray:
        """(W, L) view of a per-sample column."""
        first = int(self.starts[0]) if self.starts.size else 0
        windows = sliding_window_view(x, self.length)[first :: self.step]
        out: FloatArray = windows[: self.starts.size]
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

    def rows(self, lo: int, hi: int) -> _Samples:
        """Samples ``lo``…``hi − 1``."""
        part = slice(lo, hi)
        return _Samples(
            self.time[part],
            self.gyro[part],
            self.acc[part],
            None if self.mag is None else self.mag[part],
            None if self.md is None else self.md[part],
            self.gyro_axes,
        )

    @staticmethod
    def join(first: _Samples | None, then: _Samples) -> _Samples:
        """``first``'s samples followed by ``then``'s."""
        if first is None:
            return then
        mag = (
            None if then.mag is None or first.mag is None else np.concatenate([first.mag, then.mag])
        )
        md = None if then.md is None or first.md is None else np.concatenate([first.md, then.md])
        return _Samples(
            np.concatenate([first.time, then.time]),
            np.concatenate([first.gyro, then.gyro]),
            np.concatenate([first.acc, then.acc]),
            mag,
            md,
            then.gyro_axes,
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
    win = _Windows.of(len(data.time), data.time[0], data.time[-1], options)
    motion = _Motion.of(data, win, options)
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


def window_checks(samples: Port, site: Site, options: QcOptions = DEFAULTS) -> pa.Table:
    """Check continuous raw samples (RawSamples, a table or a stream of record batches)
    window by window (module docstring), a batch of windows at a time: the samples of the
    windows not yet checked are kept, never the survey (each window's numbers are those of
    the whole table). Returns QcResults rows with window times (station and position null,
    md the window's median MD); no samples give no rows. Raises
    :class:`~pipeline.qc.options.QcStop` when a check with policy ``stop`` fails,
    :class:`~pipeline.qc.options.QcInputError` for data shorter than a window."""
    stream = as_stream(samples)
    scan = _Scan.of(stream)
    if scan.rows == 0:
        return QcResults.compiled().schema().empty_table()
    win = _Windows.of(scan.rows, scan.first, scan.last, options)
    earth = earth_reference(site, magnetic=scan.magnetic, model=options.magnetic_model)
    found: dict[str, list[Rows]] = {"rest": [], "motion": [], "magnetic": []}
    kept: _Samples | None = None
    base = 0  # sample number of kept's first sample
    for batch in stream:
        kept = _Samples.join(kept, scan.samples(batch))
        stop = base + len(kept.time)
        part = win.shifted(base, stop)
        if part.starts.size:
            for name, rows in _check_windows(kept, part, earth, options).items():
                found[name] += rows
            following = int(part.starts[-1]) + base + win.step
            keep = min(following, stop) - base
            kept, base = kept.rows(keep, len(kept.time)), base + keep
    qc = results_table([*found["rest"], *found["motion"], *found["magnetic"]])
    raise_on_stop(qc, options)
    return qc


def _check_windows(
    data: _Samples, win: _Windows, earth: EarthReference, options: QcOptions
) -> dict[str, list[Rows]]:
    """The rows of the windows ``win`` of ``data``: checks at rest, motion bounds, magnetic."""
    motion = _Motion.of(data, win, options)
    count = len(motion.start)
    md = np.full(count, np.nan) if data.md is None else np.median(win.view(data.md), axis=1)
    keys = Keys(np.full(count, -1), np.full(count, -1), md, motion.start, motion.end)
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
    moving = np.flatnonzero(~motion.still)
    found = {
        "rest": rows,
        "motion": _motion_bounds(data, win, earth.gravity, options, keys, moving),
        "magnetic": [],
    }
    if data.mag is not None and earth.magnetic is not None:
        steady = (
            motion.still if motion.accel is None else np.abs(motion.accel) <= options.steady_accel
        )
        found["magnetic"] = _magnetic(
            win, data.mag, data.acc, earth.magnetic, options, keys, steady
        )
    return found


@dataclass
class _Scan:
    """A first pass over the samples (checked against RawSamples unless the stream holds it
    already): rows, time span and which columns have data; then each batch's columns as
    :class:`_Samples`."""

    rows: int
    first: float
    last: float
    present: set[str]
    gyro_axes: str

    @classmethod
    def of(cls, stream: TableStream) -> _Scan:
        names = [n for n in stream.column_names if n == "md" or n[:-1] in _TRIADS]
        nulls = dict.fromkeys(names, 0)
        rows, first, last = 0, np.nan, np.nan
        for batch in RawSamples.validate_stream(stream):
            if batch.num_rows:
                time = batch.column(batch.schema.get_field_index("time"))
                first = float(time[0].as_py()) if rows == 0 else first
                last = float(time[-1].as_py())
            rows += batch.num_rows
            for name in names:
                nulls[name] += batch.column(batch.schema.get_field_index(name)).null_count
        present = {n for n in names if nulls[n] < rows}
        if "md" in present and nulls["md"]:
            raise QcInputError(f"column 'md' has {nulls['md']} missing values: give all or none")
        axes = "".join(a for a in "xyz" if f"gyro_{a}" in present)
        return cls(rows, first, last, present, axes)

    @property
    def magnetic(self) -> bool:
        return all(f"mag_{a}" in self.present for a in "xyz")

    def samples(self, batch: pa.RecordBatch) -> _Samples:
        def column(name: str) -> FloatArray:
            values = batch.column(batch.schema.get_field_index(name))
            out: FloatArray = values.to_numpy(zero_copy_only=False).astype(float)
            return out

        def triad(prefix: str) -> FloatArray:
            nan = np.full(batch.num_rows, np.nan)
            names = [f"{prefix}_{a}" for a in "xyz"]
            return np.stack([column(n) if n in self.present else nan for n in names], axis=-1)

        return _Samples(
            column("time"),
            triad("gyro"),
            triad("acc"),
            triad("mag") if self.magnetic else None,
            column("md") if "md" in self.present else None,
            self.gyro_axes,
        )


_TRIADS = ("gyro_", "acc_", "mag_")


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
