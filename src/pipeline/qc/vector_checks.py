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
check instead (:mod:`pipeline.qc.engine`, with the rest limits). Each check's tolerance is
a :class:`~pipeline.qc.options.Tolerance`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray
from pipeline.qc.options import Limit, QcOptions, Tolerance
from pipeline.qc.reference import EarthReference
from pipeline.qc.sensors import Sensors

BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]
StrArray = NDArray[np.object_]


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


def norm(v: FloatArray) -> FloatArray:
    out: FloatArray = np.linalg.norm(v, axis=-1)
    return out


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    out: FloatArray = np.einsum("...i,...i->...", a, b)
    return out


def _horizontal(w: FloatArray, g: FloatArray) -> FloatArray:
    up = -g / norm(g)[..., None]
    return norm(w - _dot(w, up)[..., None] * up)


def _latitude(w: FloatArray, g: FloatArray) -> FloatArray:
    up = -g / norm(g)[..., None]
    out: FloatArray = np.degrees(np.arctan2(_dot(w, up), _horizontal(w, g)))
    return out


def _along_gravity(w: FloatArray, g: FloatArray) -> FloatArray:
    return _dot(w, g) / norm(g)


def _dip(b: FloatArray, g: FloatArray) -> FloatArray:
    sine = _dot(b, g) / (norm(b) * norm(g))
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
    "earth_rate": VectorCheck("deg/h", ("gyro",), norm, lambda e: e.rate, "|ω|"),
    "gravity": VectorCheck("m/s2", ("acc",), norm, lambda e: e.gravity, "|g|"),
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
    "magnetic_field": VectorCheck("nT", ("mag",), norm, _field, "|B|", MAGNETIC_NOTE),
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
