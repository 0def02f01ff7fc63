"""Validity checks of sensor readings at rest against the Earth references (DOMAIN.md §3).

A tool at rest measures constant, known vectors: the Earth rate ω (°/h), gravity g (m/s²,
gravity sign convention: ``g_b = C_n^b (0, 0, g)`` points down) and the geomagnetic field B
(nT). Rotation-invariant functions of the body-frame readings are compared with their
references at the site (latitude φ, normal gravity g₀, reference field F and dip δ):

===================  ============================================  ======================
check                measured                                      reference
===================  ============================================  ======================
earth_rate           |ω|                                           Ω
gravity              |g|                                           g₀ (WGS84, site)
latitude             atan2(ω·u, |ω − (ω·u) u|), u = −g/|g| (up)    φ
horizontal_rate      |ω − (ω·u) u|                                 Ω cos φ
rate_along_gravity   ω·g/|g|                                       −Ω sin φ
magnetic_field       |B|                                           F
magnetic_dip         asin(B·d/|B|), d = g/|g| (down)               δ
earth_rate_fit       k = √((u'/cos I)² + v'²) of the position fit   Ω cos φ
rest_gyro, rest_acc  largest per-axis sample std of a reading      0 (limit)
===================  ============================================  ======================

``rate_along_gravity``: ``ω_b·g_b = (C_n^b ω^n)·(C_n^b (0, 0, g)) = ω^n·(0, 0, g)`` and
``ω^n = Ω (cos φ, 0, −sin φ)``, so ``ω·g = −Ω sin φ·|g|`` (negative in the northern
hemisphere). ``latitude``, ``horizontal_rate`` and ``rate_along_gravity`` couple the gyro
and accelerometer triads: they see a misalignment between them, which the magnitudes miss.

The gyro checks (earth_rate, latitude, horizontal_rate, rate_along_gravity) need a
three-axis gyro; single-axis and XY tools get rows saying so and the ``earth_rate_fit``
check instead: their frame positions are fitted (compassing's least squares, bias and
trend removed) after removing the vertical Earth rate from each reading (``ω + Ω sin φ·g/|g|``
leaves ``Ω cos φ·n_b``, n the north direction in the body), giving
``(u', v') = Ω cos φ (cos A cos I, −sin A)`` in the high-side frame, hence k. Near vertical
(I below ``vertical_below``) the fit is referenced to the frame-angle sensor and
k ≈ √(u'² + v'²), low by at most 1 − cos I (0.14 % at 3°). Near horizontal σ_k grows as
1/cos I: the check weakens there. A fit cannot see a constant gyro bias (it removes it).

Tolerance of a reading (:class:`Tolerance`):
``√((sigma·σ)² + absolute² + (relative·|reference|)²)``, σ the standard deviation of the
measured value propagated (first order) from the σ of each mean reading, std/√n. Checks are
made per reading (station × frame position), so a fault that changes sign as the frame
turns is not averaged away; a station of N positions has N rows per check and fails when
any does (false-alarm rate per station ≈ N × the rate per row).

PositionReadings carry no magnetometers: :func:`station_checks` averages them from the raw
samples over the span of each reading (its ``n`` samples around ``t``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from pipeline.compass.precision import OMEGA_DEG_H
from pipeline.compass.solve import StationReject, fit_positions
from pipeline.earth.frames import FloatArray
from pipeline.earth.geomagnetic import ModelKey, reference_field
from pipeline.earth.site import MagneticReference, Site
from pipeline.errors import GyropipeError
from pipeline.qc.faults import Equation, Finding, isolate
from pipeline.qc.tables import STATUSES, QcResults, QcSummary
from pipeline.tables import PositionReadings
from pipeline.well import WellMetadata

BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]
StrArray = NDArray[np.object_]
Policy = Literal["flag", "drop", "stop"]

GYRO_FLOOR = 0.5
"""°/h: three times the ISCWSA GYRO-NS 1σ gyro bias (0.15 °/h), rounded up."""


class QcInputError(GyropipeError, ValueError):
    """Inputs the checks cannot use: missing site metadata, readings without what a check
    needs."""


class QcStop(GyropipeError):
    """A check whose policy is ``stop`` failed. Names the station (or window) and the check;
    carries the QC results and, for stations, the summary (for the report)."""

    def __init__(
        self, where: str, check: str, detail: str, qc: pa.Table, summary: pa.Table | None
    ) -> None:
        self.where = where
        self.check = check
        self.qc = qc
        self.summary = summary
        super().__init__(f"{where}: check {check!r} failed and its policy is stop: {detail}")


class _Options(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Tolerance(_Options):
    """Tolerance of a statistical check, in the check's unit:
    ``√((sigma·σ)² + absolute² + (relative·|reference|)²)``; and what a failure does."""

    sigma: float = Field(0.0, ge=0, description="multiples of the measured value's σ")
    absolute: float = Field(0.0, ge=0, description="absolute part, in the check's unit")
    relative: float = Field(0.0, ge=0, description="fraction of |reference|")
    policy: Policy = Field(
        "flag", description="flag; drop (exclude the station downstream); stop (raise)"
    )

    def of(self, sigma: FloatArray, reference: FloatArray) -> FloatArray:
        """Tolerance for measured values of standard deviation ``sigma``."""
        out: FloatArray = np.sqrt(
            (self.sigma * sigma) ** 2 + self.absolute**2 + (self.relative * reference) ** 2
        )
        return out


class Limit(_Options):
    """An upper limit on a non-negative quantity, and what exceeding it does."""

    limit: float = Field(gt=0, description="largest allowed value, in the check's unit")
    policy: Policy = Field("flag", description="flag, drop or stop")


class QcOptions(_Options):
    """Tolerances, limits and policies of every check, and the window settings of
    continuous data. Defaults: ``sigma`` 3 (0.27 % false alarms per reading from white
    noise alone) plus absolute floors for systematic sensor errors — gyro 0.5 °/h (≈ 3 ×
    ISCWSA GYRO-NS bias 0.15 °/h), accelerometer 0.012 m/s² (≈ 1.2 mg, 3 × a 0.004 m/s²
    bias) — and the industry magnetic tolerances (ISCWSA eBook §22.1)."""

    earth_rate: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="|ω| vs Ω, °/h"
    )
    gravity: Tolerance = Field(
        Tolerance(sigma=3, absolute=0.012), description="|g| vs normal gravity, m/s²"
    )
    latitude: Tolerance = Field(
        Tolerance(sigma=3, absolute=1.9),
        description="latitude from gyros and accelerometers vs the site's, deg (1.9° is the "
        "0.5 °/h gyro floor seen across the 15.04 °/h Earth rate)",
    )
    horizontal_rate: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="ω_h vs Ω cos φ, °/h"
    )
    rate_along_gravity: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR), description="ω·g/|g| vs −Ω sin φ, °/h"
    )
    magnetic_field: Tolerance = Field(
        Tolerance(absolute=300.0), description="|B| vs the reference total field, nT"
    )
    magnetic_dip: Tolerance = Field(
        Tolerance(absolute=0.25), description="dip vs the reference dip, deg"
    )
    earth_rate_fit: Tolerance = Field(
        Tolerance(sigma=3, absolute=GYRO_FLOOR),
        description="single-axis/XY tools: fitted horizontal Earth rate vs Ω cos φ, °/h",
    )
    rest_gyro: Limit = Field(
        Limit(limit=100.0, policy="drop"),
        description="at rest: largest per-axis sample std of the gyros, °/h (also the "
        "stationary-window threshold)",
    )
    rest_acc: Limit = Field(
        Limit(limit=0.02, policy="drop"),
        description="at rest: largest per-axis sample std of the accelerometers, m/s² (also "
        "the stationary-window threshold)",
    )
    rest_speed: float = Field(
        0.02, gt=0, description="windows: largest |dMD/dt| (LSQ slope) of a stationary one, m/s"
    )
    steady_accel: float = Field(
        0.02,
        gt=0,
        description="windows: the dip is checked only where the MD acceleration (quadratic "
        "fit) is below this, m/s² (an acceleration a tilts the measured gravity by a/g rad; "
        "without MD, only in stationary windows)",
    )
    motion_rate: Limit = Field(
        Limit(limit=100.0), description="moving windows: largest |ω| of any sample, deg/s"
    )
    motion_accel: Limit = Field(
        Limit(limit=5.0),
        description="moving windows: largest ||a| − g₀| of any sample, m/s² (a lower bound "
        "of the tool's own acceleration)",
    )
    gyro_saturation: Limit = Field(
        Limit(limit=297.0),
        description="moving windows: largest |gyro axis| of any sample, deg/s (99 % of a "
        "±300 deg/s full scale: set from the tool)",
    )
    acc_saturation: Limit = Field(
        Limit(limit=19.4),
        description="moving windows: largest |accelerometer axis| of any sample, m/s² (99 % "
        "of a ±2 g full scale: set from the tool)",
    )
    window: float = Field(10.0, gt=0, description="length of a continuous-data window, s")
    step: float = Field(5.0, gt=0, description="step between window starts, s")
    vertical_below: float = Field(
        3.0,
        gt=0,
        lt=45,
        description="earth_rate_fit: inclination below which the fit is "
        "referenced to the frame angle, deg",
    )
    fit_trend: bool = Field(True, description="earth_rate_fit: fit a linear gyro trend too")
    isolation_margin: float = Field(
        1.0,
        gt=0,
        description="fault isolation: how much better (sum of squared residuals in units of "
        "their tolerance) the best sensor must explain a station than the runner-up",
    )
    magnetic_model: ModelKey = Field(
        "wmm2025", description="geomagnetic model when the site gives no magnetic reference"
    )


DEFAULTS = QcOptions()

CHECKS = (
    "earth_rate",
    "gravity",
    "latitude",
    "horizontal_rate",
    "rate_along_gravity",
    "magnetic_field",
    "magnetic_dip",
    "earth_rate_fit",
    "rest_gyro",
    "rest_acc",
    "motion_rate",
    "motion_accel",
    "gyro_saturation",
    "acc_saturation",
)
"""Every check, in report order; each is the name of its option in :class:`QcOptions`."""
FIT_UNDETERMINED = (
    "the fit removes gyro biases and one or two gyro axes cannot be told apart: a scale "
    "error, motion or a frame fault"
)
"""Diagnosis of a failed earth_rate_fit (single-axis and XY tools are not isolated)."""
ISOLATED = ("earth_rate", "gravity", "latitude", "horizontal_rate", "rate_along_gravity")
"""Checks whose failure starts fault isolation (:mod:`pipeline.qc.faults`)."""


@dataclass(frozen=True)
class EarthReference:
    """What a tool at rest at the site should measure."""

    rate: float
    """Ω, °/h"""
    latitude: float
    """φ, deg"""
    gravity: float
    """normal gravity at the wellhead, m/s²"""
    magnetic: MagneticReference | None
    """reference field (total field nT, dip deg), when magnetometers are checked"""


def earth_reference(site: Site, *, magnetic: bool, model: ModelKey = "wmm2025") -> EarthReference:
    """References at ``site``; with ``magnetic``, the site's field or else ``model`` at the
    wellhead and survey date (raises :class:`~pipeline.earth.geomagnetic.ModelValidityError`
    for a date outside the model). Gravity and field are the wellhead's: at a few km depth
    gravity changes by < 1e-5 m/s² and the main field by ~0.03 nT/m, both well inside the
    default tolerances."""
    reference = None
    if magnetic:
        reference = site.magnetic
        if reference is None:
            if site.date is None:
                raise QcInputError("magnetometer checks need the survey date (field model)")
            reference = reference_field(
                site.latitude, site.longitude, site.elevation, site.date, model=model
            ).reference()
    return EarthReference(OMEGA_DEG_H, site.latitude, site.gravity, reference)


def site_from_well(
    well: WellMetadata, magnetic: MagneticReference | None = None, *, field: bool = True
) -> Site:
    """The QC site of a well: latitude and survey date are required, and so is the longitude
    when the geomagnetic model is needed (``field`` and no ``magnetic`` reference given). The well's
    elevation (above sea level) stands in for the ellipsoidal height: the geoid's tens of
    metres change gravity by < 1e-4 m/s². Raises :class:`QcInputError` naming what is
    missing."""
    missing = [
        what
        for what, absent in (
            ("latitude", well.latitude is None),
            ("survey_date (for the geomagnetic model)", field and well.survey_date is None),
            (
                "longitude (for the geomagnetic model)",
                field and well.longitude is None and not magnetic,
            ),
        )
        if absent
    ]
    if missing:
        raise QcInputError(
            "validity checks need the well's " + ", ".join(missing) + ": set them in the file "
            "header, the pipeline's `well:` or --well"
        )
    assert well.latitude is not None
    return Site(
        latitude=well.latitude,
        longitude=well.longitude or 0.0,
        elevation=well.elevation or 0.0,
        date=well.survey_date,
        magnetic=magnetic,
    )


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


@dataclass(frozen=True)
class Keys:
    """Where each evaluated row belongs: station/position (−1: none), md (NaN: unknown),
    window start/end times (NaN: not a window)."""

    station: IntArray
    position: IntArray
    md: FloatArray
    start: FloatArray
    end: FloatArray

    def take(self, index: IntArray) -> Keys:
        return Keys(
            *(getattr(self, n)[index] for n in ("station", "position", "md", "start", "end"))
        )


@dataclass
class Rows:
    """Evaluations of one check on R readings, stations or windows (QcResults columns as
    arrays; station/position −1 and md/window NaN when not applicable)."""

    check: str
    unit: str
    measured: FloatArray
    reference: FloatArray
    tolerance: FloatArray
    evaluated: BoolArray
    detail: StrArray
    keys: Keys
    suspect: StrArray = field(init=False)

    def __post_init__(self) -> None:
        self.suspect = np.full(len(self.measured), "", dtype=object)

    @property
    def failed(self) -> BoolArray:
        with np.errstate(invalid="ignore"):
            out: BoolArray = self.evaluated & ~(
                np.abs(self.measured - self.reference) <= self.tolerance
            )
        return out


def propagate(
    func: Callable[..., FloatArray], inputs: list[FloatArray], sigmas: list[FloatArray]
) -> tuple[FloatArray, FloatArray]:
    """``func(*inputs)`` (each input (R, 3), output (R,)) and its first-order standard
    deviation from independent per-axis σ of the inputs (central differences, step 1e-6 of
    each vector's norm). NaN σ count as zero."""
    value = func(*inputs)
    var = np.zeros_like(value)
    for i, (x, s) in enumerate(zip(inputs, sigmas, strict=True)):
        h = 1e-6 * np.maximum(np.linalg.norm(x, axis=-1), 1e-300)
        for j in range(3):
            step = np.zeros_like(x)
            step[:, j] = h
            up = [*inputs[:i], x + step, *inputs[i + 1 :]]
            down = [*inputs[:i], x - step, *inputs[i + 1 :]]
            slope = (func(*up) - func(*down)) / (2 * h)
            var += (slope * np.nan_to_num(s[:, j])) ** 2
    return value, np.sqrt(var)


def _norm(v: FloatArray) -> FloatArray:
    out: FloatArray = np.linalg.norm(v, axis=-1)
    return out


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    out: FloatArray = np.einsum("...i,...i->...", a, b)
    return out


def _horizontal(w: FloatArray, g: FloatArray) -> FloatArray:
    up = -g / _norm(g)[..., None]
    return _norm(w - _dot(w, up)[..., None] * up)


def _latitude(w: FloatArray, g: FloatArray) -> FloatArray:
    up = -g / _norm(g)[..., None]
    out: FloatArray = np.degrees(np.arctan2(_dot(w, up), _horizontal(w, g)))
    return out


def _along_gravity(w: FloatArray, g: FloatArray) -> FloatArray:
    return _dot(w, g) / _norm(g)


def _dip(b: FloatArray, g: FloatArray) -> FloatArray:
    sine = _dot(b, g) / (_norm(b) * _norm(g))
    out: FloatArray = np.degrees(np.arcsin(np.clip(sine, -1.0, 1.0)))
    return out


@dataclass(frozen=True)
class VectorCheck:
    """A check on mean vectors: its unit, the triads it uses, the measured function of
    them and its reference."""

    unit: str
    sensors: tuple[Literal["gyro", "acc", "mag"], ...]
    func: Callable[..., FloatArray]
    reference: Callable[[EarthReference], float]
    symbol: str
    note: str = ""
    """appended to the detail of a failure"""


MAGNETIC_NOTE = "a magnetometer fault or magnetic interference (not told apart)"


def _field(e: EarthReference) -> float:
    assert e.magnetic is not None
    return e.magnetic.total_field


def _ref_dip(e: EarthReference) -> float:
    assert e.magnetic is not None
    return e.magnetic.dip


VECTOR_CHECKS: dict[str, VectorCheck] = {
    "earth_rate": VectorCheck("deg/h", ("gyro",), _norm, lambda e: e.rate, "|ω|"),
    "gravity": VectorCheck("m/s2", ("acc",), _norm, lambda e: e.gravity, "|g|"),
    "latitude": VectorCheck("deg", ("gyro", "acc"), _latitude, lambda e: e.latitude, "φ"),
    "horizontal_rate": VectorCheck(
        "deg/h",
        ("gyro", "acc"),
        _horizontal,
        lambda e: e.rate * np.cos(np.radians(e.latitude)),
        "ω_h",
    ),
    "rate_along_gravity": VectorCheck(
        "deg/h",
        ("gyro", "acc"),
        _along_gravity,
        lambda e: -e.rate * np.sin(np.radians(e.latitude)),
        "ω·g/|g|",
    ),
    "magnetic_field": VectorCheck("nT", ("mag",), _norm, _field, "|B|", MAGNETIC_NOTE),
    "magnetic_dip": VectorCheck("deg", ("mag", "acc"), _dip, _ref_dip, "dip", MAGNETIC_NOTE),
}


def vector_checks(
    sensors: Sensors, earth: EarthReference, options: QcOptions, keys: Keys
) -> list[Rows]:
    """The checks on mean vectors (module table), one row per reading. Gyro checks of a tool
    without three gyro axes give rows saying why they were skipped; magnetic checks run
    only when there are magnetometers."""
    out: list[Rows] = []
    n = len(sensors.acc)
    axes = sensors.gyro_axes
    for name, spec in VECTOR_CHECKS.items():
        if "mag" in spec.sensors and (sensors.mag is None or earth.magnetic is None):
            continue
        reference = np.full(n, spec.reference(earth))
        if "gyro" in spec.sensors and axes != "xyz":
            out.append(
                Rows(
                    name,
                    spec.unit,
                    np.full(n, np.nan),
                    reference,
                    np.full(n, np.nan),
                    np.zeros(n, bool),
                    np.full(
                        n,
                        f"skipped: {spec.symbol} needs a three-axis gyro; this tool has "
                        f"gyro axes {axes!r} (see earth_rate_fit)",
                        dtype=object,
                    ),
                    keys,
                )
            )
            continue
        triads = {
            "gyro": (sensors.gyro, sensors.gyro_sigma),
            "acc": (sensors.acc, sensors.acc_sigma),
        }
        if sensors.mag is not None and sensors.mag_sigma is not None:
            triads["mag"] = (sensors.mag, sensors.mag_sigma)
        inputs = [triads[s][0] for s in spec.sensors]
        errors = [triads[s][1] for s in spec.sensors]
        measured, sigma = propagate(spec.func, inputs, errors)
        unknown = np.any(np.isnan(np.concatenate(errors, axis=1)), axis=1, keepdims=False)
        out.append(
            judge(
                name,
                spec.unit,
                spec.symbol,
                measured,
                sigma,
                unknown,
                reference,
                getattr(options, name),
                keys,
                spec.note,
            )
        )
    return out


def judge(
    name: str,
    unit: str,
    symbol: str,
    measured: FloatArray,
    sigma: FloatArray,
    sigma_unknown: BoolArray,
    reference: FloatArray,
    tolerance: Tolerance,
    keys: Keys,
    note: str = "",
) -> Rows:
    """Rows of a statistical check: tolerance, pass/fail and the detail of each row
    (``note`` is appended to failures)."""
    tol = tolerance.of(sigma, reference)
    evaluated = tol > 0
    detail = np.full(len(measured), "", dtype=object)
    detail[sigma_unknown & (tolerance.sigma > 0)] = "σ unknown (no std/n): no σ term"
    detail[~evaluated] = "skipped: σ unknown and no absolute or relative tolerance"
    rows = Rows(name, unit, measured, reference, tol, evaluated, detail, keys)
    for i in np.flatnonzero(rows.failed):
        off = measured[i] - reference[i]
        detail[i] = (
            f"{symbol} = {measured[i]:.6g} {unit}, {off:+.3g} {unit} off the reference "
            f"{reference[i]:.6g} ({abs(off) / tol[i]:.1f} × tolerance)"
            + "".join(f"; {text}" for text in (detail[i], note) if text)
        )
    return rows


def limit_rows(
    name: str, unit: str, what: str, measured: FloatArray, limit: Limit, keys: Keys
) -> Rows:
    """Rows of a limit check: ``measured ≤ limit`` (reference 0)."""
    n = len(measured)
    evaluated = ~np.isnan(measured)
    detail = np.full(n, "", dtype=object)
    rows = Rows(name, unit, measured, np.zeros(n), np.full(n, limit.limit), evaluated, detail, keys)
    for i in np.flatnonzero(rows.failed):
        detail[i] = f"{what} {measured[i]:.4g} {unit} exceeds the limit {limit.limit:g} {unit}"
    return rows


def _column(table: pa.Table, name: str) -> FloatArray:
    """A float column as an array (NaN where null or absent)."""
    if name not in table.column_names:
        return np.full(table.num_rows, np.nan)
    values: FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


def readings_sensors(readings: pa.Table, samples: pa.Table | None = None) -> Sensors:
    """Sensor means and σ of PositionReadings rows; magnetometers averaged from the raw
    ``samples`` over each reading's span (see :func:`magnetic_means`) when given."""
    n = _column(readings, "n")

    def triad(prefix: str) -> tuple[FloatArray, FloatArray]:
        mean = np.stack([_column(readings, f"{prefix}_{a}") for a in "xyz"], axis=-1)
        std = np.stack([_column(readings, f"{prefix}_{a}_std") for a in "xyz"], axis=-1)
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
    n = _column(readings, "n").astype(int)
    rate = n / _column(readings, "duration")
    half = (n - 1) / (2 * rate) + 0.25 / rate
    t = _column(readings, "t")
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
    mag = np.stack([_column(samples, f"mag_{a}") for a in "xyz"], axis=-1)
    if len(n) == 0:
        return np.empty((0, 3)), np.empty((0, 3))
    index = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    offsets = np.concatenate([[0], np.cumsum(n)[:-1]])
    values = mag[index]
    mean = np.add.reduceat(values, offsets, axis=0) / n[:, None]
    dev = values - np.repeat(mean, n, axis=0)
    std = np.sqrt(np.add.reduceat(dev**2, offsets, axis=0) / np.maximum(n - 1, 1)[:, None])
    return mean, std / np.sqrt(n)[:, None]


def rest_checks(readings: pa.Table, options: QcOptions, keys: Keys) -> list[Rows]:
    """The tool must be still while a reading is averaged: the largest per-axis sample std
    of the gyros (°/h) and accelerometers (m/s²) against the rest limits."""
    out = []
    for name, prefix, unit in (("rest_gyro", "gyro", "deg/h"), ("rest_acc", "acc", "m/s2")):
        std = np.stack([_column(readings, f"{prefix}_{a}_std") for a in "xyz"], axis=-1)
        largest = np.full(len(std), np.nan)
        known = ~np.isnan(std).all(axis=1)
        largest[known] = np.nanmax(std[known], axis=1)
        rows = limit_rows(name, unit, f"{prefix} sample std", largest, getattr(options, name), keys)
        rows.detail[~known] = "skipped: the readings carry no std columns"
        out.append(rows)
    return out


def fit_checks(
    readings: pa.Table, sensors: Sensors, earth: EarthReference, options: QcOptions
) -> Rows:
    """``earth_rate_fit`` per station of a single-axis or XY tool (module docstring)."""
    m = 2 if "y" in sensors.gyro_axes else 1  # transverse gyros: x, or x and y
    station = readings.column("station").to_numpy()
    starts = np.flatnonzero(np.r_[True, station[1:] != station[:-1]])
    ends = np.r_[starts[1:], len(station)]
    t = _column(readings, "t")
    frame = _column(readings, "frame_angle")
    md = _column(readings, "md")
    lat = np.radians(earth.latitude)
    reference = earth.rate * np.cos(lat)
    inc_k, sigma_inc_k = propagate(
        lambda g: np.arctan2(np.hypot(g[:, 0], g[:, 1]), g[:, 2]),
        [sensors.acc],
        [sensors.acc_sigma],
    )
    down = sensors.acc / _norm(sensors.acc)[:, None]
    gyro = sensors.gyro[:, :m] + earth.rate * np.sin(lat) * down[:, :m]  # Ω cos φ · n_b
    sigma = sensors.gyro_sigma[:, :m]
    s = len(starts)
    measured, sig = np.full(s, np.nan), np.full(s, np.nan)
    detail = np.full(s, "", dtype=object)
    for i, (a, b) in enumerate(zip(starts, ends, strict=True)):
        inc = float(np.mean(inc_k[a:b]))
        near = min(inc, np.pi - inc) < np.radians(options.vertical_below)
        if not np.all(np.isfinite(sigma[a:b])):
            detail[i] = "skipped: the readings carry no gyro std/n (the fit needs σ)"
            continue
        if near and np.isnan(frame[a:b]).any():
            detail[i] = "skipped: near vertical and no frame angle to reference the fit"
            continue
        alpha = (
            np.radians(frame[a:b])
            if near
            else np.arctan2(sensors.acc[a:b, 1], -sensors.acc[a:b, 0])
        )
        n_obs = (b - a) * m
        terms = 2 if options.fit_trend and n_obs >= 2 + 2 * m else 1
        try:
            fit = fit_positions(alpha, t[a:b], gyro[a:b], sigma[a:b], terms)
        except StationReject as exc:
            detail[i] = f"skipped: {exc}"
            continue
        u, v = fit.uv
        c = 1.0 if near else np.cos(inc)
        k = np.hypot(u / c, v)
        jac = np.array([u / (c * c * k), v / k])
        var = jac @ fit.cov[:2, :2] @ jac
        if not near:  # through I: ∂k/∂I = u² sin I / (k cos³ I)
            sigma_inc = np.sqrt(np.sum(sigma_inc_k[a:b] ** 2)) / (b - a)
            var += (u * u * np.sin(inc) / (k * c**3) * sigma_inc) ** 2
        measured[i], sig[i] = k, np.sqrt(var)
    keys = Keys(station[starts], np.full(s, -1), md[starts], np.full(s, np.nan), np.full(s, np.nan))
    rows = judge(
        "earth_rate_fit",
        "deg/h",
        "k",
        measured,
        np.nan_to_num(sig),
        np.zeros(s, bool),
        np.full(s, reference),
        options.earth_rate_fit,
        keys,
    )
    skipped = np.isnan(measured)
    rows.evaluated &= ~skipped
    rows.detail[skipped] = detail[skipped]
    failed = rows.failed
    rows.suspect[failed] = "undetermined"
    rows.detail[failed] = [f"{text}; {FIT_UNDETERMINED}" for text in rows.detail[failed]]
    return rows


def _reader(spec: VectorCheck) -> Callable[[FloatArray, FloatArray], FloatArray]:
    """A check's function as a function of (ω, g)."""

    def func(w: FloatArray, g: FloatArray) -> FloatArray:
        return spec.func(*[w if s == "gyro" else g for s in spec.sensors])

    return func


def isolate_rows(
    rows: list[Rows],
    group: IntArray,
    sensors: Sensors,
    earth: EarthReference,
    options: QcOptions,
) -> dict[int, Finding]:
    """Fault isolation for every group (station, or window) with a failed gyro or
    accelerometer check: the readings of each group are stacked as frame positions and
    handed to :func:`pipeline.qc.faults.isolate`. Fills ``suspect`` and appends the
    diagnosis to the detail of those failed rows; returns the finding of each group."""
    by_name = {r.check: r for r in rows}
    failing = np.zeros(len(group), bool)
    for name in ISOLATED:
        if name in by_name:
            failing |= by_name[name].failed
    groups = np.unique(group[failing])
    if groups.size == 0:
        return {}
    members = [np.flatnonzero(group == g) for g in groups]
    width = max(len(m) for m in members)
    index = np.zeros((len(groups), width), dtype=np.int64)
    valid = np.zeros((len(groups), width), dtype=bool)
    for i, m in enumerate(members):
        index[i, : len(m)], valid[i, : len(m)] = m, True
    equations = []
    for name in ISOLATED:
        if name in by_name and by_name[name].evaluated.any():
            spec = VECTOR_CHECKS[name]
            tol = np.where(by_name[name].evaluated, by_name[name].tolerance, np.inf)
            equations.append(
                Equation(
                    "gyro" in spec.sensors,
                    _reader(spec),
                    float(by_name[name].reference[0]),
                    tol[index],
                )
            )
    three_axis = sensors.gyro_axes == "xyz"
    findings = isolate(
        sensors.gyro[index] if three_axis else None,
        sensors.acc[index],
        valid,
        equations,
        options.isolation_margin,
    )
    result = {int(g): f for g, f in zip(groups, findings, strict=True)}
    for name in ISOLATED:
        if name not in by_name:
            continue
        r = by_name[name]
        for row in np.flatnonzero(r.failed):
            finding = result[int(group[row])]
            r.suspect[row] = finding.suspect
            r.detail[row] = f"{r.detail[row]}; {finding.diagnosis}"
    return result


def results_table(rows: list[Rows]) -> pa.Table:
    """QcResults from evaluated rows, sorted by station, window start, position (station-
    level rows after the positions) and check."""

    def join(get: Callable[[Rows], NDArray[Any]]) -> NDArray[Any]:
        return np.concatenate([get(r) for r in rows])

    station, position = join(lambda r: r.keys.station), join(lambda r: r.keys.position)
    md, start, end = (
        join(lambda r: r.keys.md),
        join(lambda r: r.keys.start),
        join(lambda r: r.keys.end),
    )
    check = join(lambda r: np.full(len(r.measured), r.check, dtype=object))
    rank = join(lambda r: np.full(len(r.measured), CHECKS.index(r.check)))
    last = np.iinfo(np.int64).max
    order = np.lexsort(
        (rank, np.where(position < 0, last, position), np.nan_to_num(start), station)
    )
    station, position, md, start, end = (a[order] for a in (station, position, md, start, end))
    evaluated = join(lambda r: r.evaluated)[order]
    return QcResults.compiled().make_table(
        {
            "station": pa.array(station, pa.int64(), mask=station < 0),
            "position": pa.array(position, pa.int64(), mask=position < 0),
            "window_start": pa.array(start, pa.float64(), mask=np.isnan(start)),
            "window_end": pa.array(end, pa.float64(), mask=np.isnan(end)),
            "md": pa.array(md, pa.float64(), mask=np.isnan(md)),
            "check": pa.array(check[order], pa.string()),
            "measured": join(lambda r: r.measured)[order],
            "reference": join(lambda r: r.reference)[order],
            "tolerance": join(lambda r: r.tolerance)[order],
            "unit": pa.array(
                join(lambda r: np.full(len(r.measured), r.unit, dtype=object))[order], pa.string()
            ),
            "passed": pa.array(~join(lambda r: r.failed)[order], pa.bool_(), mask=~evaluated),
            "suspect": pa.array(join(lambda r: r.suspect)[order], pa.string()),
            "detail": pa.array(join(lambda r: r.detail)[order], pa.string()),
        }
    )


def station_checks(
    readings: pa.Table,
    site: Site,
    options: QcOptions = DEFAULTS,
    *,
    samples: pa.Table | None = None,
) -> tuple[pa.Table, pa.Table]:
    """Check every reading of a point survey (PositionReadings) at ``site``. With the raw
    ``samples`` the readings came from, magnetometers are averaged from them and checked.
    Returns the QcResults rows and the QcSummary per station; raises :class:`QcStop` when a
    check whose policy is ``stop`` fails (the exception carries both tables)."""
    PositionReadings.validate_table(readings)
    sensors = readings_sensors(readings, samples)
    earth = earth_reference(site, magnetic=sensors.mag is not None, model=options.magnetic_model)
    n = readings.num_rows
    station = readings.column("station").to_numpy().astype(np.int64)
    md = _column(readings, "md")
    keys = Keys(
        station,
        readings.column("position").to_numpy().astype(np.int64),
        md,
        np.full(n, np.nan),
        np.full(n, np.nan),
    )
    rows = vector_checks(sensors, earth, options, keys) + rest_checks(readings, options, keys)
    if sensors.gyro_axes != "xyz" and n:
        rows.append(fit_checks(readings, sensors, earth, options))
    findings = isolate_rows(rows, station, sensors, earth, options)
    for r in rows:
        if r.check == "earth_rate_fit":
            for s in r.keys.station[r.failed]:
                findings.setdefault(int(s), Finding("undetermined", FIT_UNDETERMINED))
    qc = results_table(rows)
    summary = _summary(rows, station, md, findings, options)
    raise_on_stop(qc, options, summary)
    return qc, summary


def _summary(
    rows: list[Rows],
    station: IntArray,
    md: FloatArray,
    findings: dict[int, Finding],
    options: QcOptions,
) -> pa.Table:
    """QcSummary: per station the most severe policy among its failed checks."""
    ids, first = np.unique(station, return_index=True)
    failed: dict[int, set[str]] = {int(s): set() for s in ids}
    for r in rows:
        for s in np.unique(r.keys.station[r.failed]):
            failed[int(s)].add(r.check)
    severity = {s: i for i, s in enumerate(STATUSES)}
    status = []
    for s in ids.tolist():
        policies = [getattr(options, c).policy for c in failed[s]]
        status.append(max(["ok", *policies], key=severity.__getitem__))
    order = {name: i for i, name in enumerate(CHECKS)}
    empty = Finding("", "")
    return QcSummary.compiled().make_table(
        {
            "station": ids,
            "md": md[first],
            "status": status,
            "failed_checks": [
                ",".join(sorted(failed[s], key=order.__getitem__)) for s in ids.tolist()
            ],
            "suspect": [findings.get(s, empty).suspect for s in ids.tolist()],
            "diagnosis": [findings.get(s, empty).diagnosis for s in ids.tolist()],
        }
    )


def raise_on_stop(qc: pa.Table, options: QcOptions, summary: pa.Table | None = None) -> None:
    """Raise :class:`QcStop` for the first failed row (in table order) of a check whose
    policy is ``stop``."""
    stopping = [c for c in CHECKS if getattr(options, c).policy == "stop"]
    if not stopping or qc.num_rows == 0:
        return
    failed = pc.and_(
        pc.is_in(qc.column("check"), pa.array(stopping)),
        pc.equal(pc.fill_null(qc.column("passed"), True), False),
    )
    hits = np.flatnonzero(failed.to_numpy(zero_copy_only=False))
    if hits.size == 0:
        return
    row = qc.slice(int(hits[0]), 1).to_pylist()[0]
    where = (
        f"station {row['station']}"
        if row["station"] is not None
        else f"window {row['window_start']:g}–{row['window_end']:g} s"
    ) + (f" (md {row['md']:g} m)" if row["md"] is not None else "")
    raise QcStop(where, row["check"], row["detail"], qc, summary)


def drop_stations(table: pa.Table, summary: pa.Table) -> pa.Table:
    """``table`` (any table with a ``station`` column) without the stations whose summary
    status is ``drop``."""
    status = summary.column("status").to_numpy(zero_copy_only=False)
    dropped = summary.column("station").to_numpy()[status == "drop"]
    keep = ~np.isin(table.column("station").to_numpy(zero_copy_only=False), dropped)
    return table.filter(pa.array(keep))
