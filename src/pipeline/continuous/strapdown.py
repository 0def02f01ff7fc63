"""Strapdown attitude of a three-axis gyro tool in continuous mode (DOMAIN.md §2, §6).

The attitude ``C_b^n`` (body b → NED n, the wellhead's local-level frame, Earth-fixed: the
transport rate of a logging tool, < 0.04 °/h at 1 m/s, is neglected as in the simulator) obeys

    Ċ_b^n = C_b^n [ω_ib^b ×] − [ω_ie^n ×] C_b^n,   ω_ie^n = Ω (cos φ, 0, −sin φ)

whose solution splits exactly into a body part and a navigation-frame part:
``C(t) = exp(−[ω_ie^n ×](t − t₀)) · C(t₀) · B(t)`` with ``Ḃ = B [ω_ib^b ×]``. B is the
ordered product of per-step rotations. Each step's rotation vector is the integral of the
rate over the step (the cubic through the four nearest rate samples) plus the second-order
coning term of the two samples bounding it:

    φ_k = ∫ω dt + (ω_k × ω_{k+1})·Δt²/12,   ∫ω dt = (ω_k + ω_{k+1})·Δt/2
          + (−ω_{k−1} + ω_k + ω_{k+1} − ω_{k+2})·Δt/24

and is turned into a rotation exactly (no small-angle truncation). The running product is a
parallel prefix scan of quaternions (log₂ n vectorised passes; rounding grows as log n).
A rate that jumps between two samples (the junction of two arcs) costs about jump·Δt/2 of
attitude whatever the rule: sample fast enough for the doglegs logged.

Nothing is divided by sin I: the attitude is integrated straight through vertical. The angles
are read off the attitude: the tool axis is the third column, ``(sin I cos A, sin I sin A,
cos I)``, so ``I = atan2(√(C₀₂² + C₁₂²), C₂₂)`` and ``A = atan2(C₁₂, C₀₂)`` — the direction
of the tool axis's horizontal projection, which near vertical is ill-conditioned (an attitude
error ε moves it by ε/sin I) and at exactly vertical undefined; the gravity toolface of frame
x is ``ψ = atan2(C₂₁, −C₂₀)`` (the third row is the unit gravity vector in the body frame).
Below ``vertical_below`` the samples are flagged ``FLAG_AZIMUTH_UNDEFINED``: the azimuth
reported there is still that horizontal direction (what minimum curvature needs, as sin I
times it), never held; the well-defined quantity there is the whole attitude.

Closure: the integrated attitude at the end stop differs from the stop's own attitude by a
rotation ``exp([φ ×])`` in the navigation frame (the misclosure); it is removed linearly in
time, ``C ← exp(−w [φ ×]) C`` with ``w = (t − t₀)/(T − t₀)``, which cancels exactly an error
growing at a constant rate in the navigation frame (a gyro bias at a steady attitude).

The run (:func:`strapdown_run`) is integrated from the start stop's first frame position
to the end stop's first frame position, the samples where compassing reports the stops'
attitude: azimuth from the compassed stop (near vertical: from the north-referenced
toolface, which the compassed azimuth and the first position's gravity toolface carry
exactly), inclination and gravity toolface ψ₀ from the accelerometers. The frame turns at
the stops are integrated like any other motion. Samples without frame-position markers are
tied at the run's first and last stop samples instead, with I and ψ from the accelerometers
there — possible only for inclined stops.

Units: times s, rates rad/s, angles rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.run import DEG_H, ContinuousError, RunStops, float_column, wrap_angle
from pipeline.continuous.tables import FLAG_AZIMUTH_UNDEFINED
from pipeline.earth.frames import FloatArray, body_to_ned, earth_rate_ned, inclination_toolface

__all__ = [
    "StrapdownRun",
    "attitude_angles",
    "close_attitude",
    "misclosure_vector",
    "propagate_attitude",
    "strapdown_run",
]


def step_rotations(t: FloatArray, rates: FloatArray) -> FloatArray:
    """Rotation vectors (n − 1, 3), rad, of the body over each sample interval from body rates
    (n, 3), rad/s, sampled at times ``t`` (n,), s: the integral of the rate plus the
    second-order coning term ``(ω_k × ω_{k+1})·Δt²/12``. The integral is that of the cubic
    through the four nearest samples (one-sided at the ends; fourth order for uniform
    sampling; the trapezoid for fewer than four samples). A rate that jumps between two
    samples (a junction of two arcs) costs about jump·Δt/2 whatever the rule."""
    dt = np.diff(t)[:, None]
    w0, w1 = rates[:-1], rates[1:]
    area = (w0 + w1) / 2
    if len(rates) >= 4:
        w = rates
        area[1:-1] += (-w[:-3] + w[1:-2] + w[2:-1] - w[3:]) / 24
        area[0] += (-3 * w[0] + 7 * w[1] - 5 * w[2] + w[3]) / 24
        area[-1] += (w[-4] - 5 * w[-3] + 7 * w[-2] - 3 * w[-1]) / 24
    phi: FloatArray = area * dt + np.cross(w0, w1) * (dt**2 / 12)
    return phi


def _quat_product(p: FloatArray, q: FloatArray) -> FloatArray:
    """Hamilton products p·q of quaternions (n, 4), scalar last (the rotation q, then p)."""
    (x1, y1, z1, w1), (x2, y2, z2, w2) = p.T, q.T
    product: FloatArray = np.stack(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ],
        axis=1,
    )
    return product


def _running_product(quats: FloatArray) -> FloatArray:
    """Inclusive ordered products q₀, q₀q₁, q₀q₁q₂, … of unit quaternions (n, 4), scalar
    last (Hillis–Steele scan: each pass composes every element with the one ``d`` before it;
    renormalised once at the end)."""
    out = quats.copy()
    d = 1
    while d < len(out):
        out[d:] = _quat_product(out[:-d], out[d:])
        d *= 2
    normalised: FloatArray = out / np.linalg.norm(out, axis=1, keepdims=True)
    return normalised


def propagate_attitude(
    t: FloatArray, rates: FloatArray, c0: FloatArray, earth_rate: FloatArray
) -> FloatArray:
    """Attitudes ``C_b^n`` (n, 3, 3) at the sample times ``t`` (n,), s, from the attitude
    ``c0`` (3, 3) at ``t[0]``, the body rates ω_ib^b (n, 3), rad/s, and the Earth rate in the
    navigation frame ``earth_rate`` (3,), rad/s."""
    steps = Rotation.from_rotvec(step_rotations(t, rates)).as_quat()
    body = np.concatenate([[[0.0, 0.0, 0.0, 1.0]], _running_product(steps)])
    nav = Rotation.from_rotvec(-(t - t[0])[:, None] * np.asarray(earth_rate)[None, :])
    attitude: FloatArray = (nav * Rotation.from_matrix(c0) * Rotation.from_quat(body)).as_matrix()
    return attitude


def misclosure_vector(integrated: FloatArray, reference: FloatArray) -> FloatArray:
    """Rotation vector φ (3,), rad, NED, with ``integrated = exp([φ ×]) · reference``."""
    phi: FloatArray = Rotation.from_matrix(integrated @ reference.T).as_rotvec()
    return phi


def close_attitude(attitude: FloatArray, t: FloatArray, misclosure: FloatArray) -> FloatArray:
    """Attitudes (n, 3, 3) with the misclosure φ (3,) removed linearly in time ``t`` (n,)."""
    w = (t - t[0]) / (t[-1] - t[0])
    closed: FloatArray = Rotation.from_rotvec(-w[:, None] * misclosure[None, :]).as_matrix()
    return closed @ attitude


def attitude_angles(attitude: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Inclination, azimuth (direction of the tool axis's horizontal projection, in (−π, π])
    and gravity toolface of frame x, rad, of attitudes ``C_b^n`` (n, 3, 3)."""
    axis = attitude[:, :, 2]
    inc = np.arctan2(np.hypot(axis[:, 0], axis[:, 1]), axis[:, 2])
    azi = np.arctan2(axis[:, 1], axis[:, 0])
    toolface = np.arctan2(attitude[:, 2, 1], -attitude[:, 2, 0])
    return inc, azi, toolface


@dataclass(frozen=True)
class StrapdownRun:
    """Attitude of the moving run at every sample from the start stop's last sample to the end
    stop's first (closure applied if asked): angles rad, flags ``FLAG_*`` of
    :mod:`pipeline.continuous.tables`."""

    inc: FloatArray
    azi: FloatArray
    toolface: FloatArray
    flags: NDArray[np.int64]
    misclosure: float
    """Heading misclosure, rad: integrated minus end-stop azimuth at an inclined end stop,
    else the misclosure's rotation about the vertical."""


def strapdown_run(
    samples: pa.Table,
    stops: RunStops,
    run: tuple[int, int],
    latitude: float,
    options: ContinuousOptions,
) -> StrapdownRun:
    """Integrate the attitude of a three-axis tool between its compassed ``stops`` (start,
    end: as from :func:`pipeline.continuous.run.compassed_stop`) across the ``run`` (index of
    the start stop's last sample, of the end stop's first sample)."""
    station = float_column(samples, "station")
    (begin, end), (start, finish) = run, stops
    first, c_first = _tie(samples, station, start, begin, options)
    last, c_last = _tie(samples, station, finish, end, options)
    span = slice(first, last + 1)
    t = float_column(samples, "time")[span]
    rates = np.stack([float_column(samples, f"gyro_{a}")[span] for a in "xyz"], axis=-1) * DEG_H
    attitude = propagate_attitude(t, rates, c_first, earth_rate_ned(np.radians(latitude)))
    phi = misclosure_vector(attitude[-1], c_last)
    if np.sin(np.radians(finish["inc"])) >= np.sin(np.radians(options.vertical_below)):
        _, end_azi, _ = attitude_angles(attitude[-1:])
        misclosure = float(wrap_angle(end_azi[0] - np.radians(finish["azi"])))
    else:  # the azimuth means nothing there: the heading part of the rotation
        misclosure = float(phi[2])
    if options.closure:
        attitude = close_attitude(attitude, t, phi)
    inc, azi, toolface = attitude_angles(attitude[begin - first : end - first + 1])
    flags = np.where(
        np.sin(inc) < np.sin(np.radians(options.vertical_below)), FLAG_AZIMUTH_UNDEFINED, 0
    ).astype(np.int64)
    return StrapdownRun(inc, azi, toolface, flags, misclosure)


def _tie(
    samples: pa.Table,
    station: FloatArray,
    stop: dict[str, float],
    boundary: int,
    options: ContinuousOptions,
) -> tuple[int, FloatArray]:
    """Sample index and attitude ``C_b^n`` where the run is tied to a compassed stop: the
    middle of the stop's first frame position (the compassed toolface's), else — with no
    position markers — the stop's sample next to the moving run."""
    stop_id = station[boundary]
    if "position" in samples.column_names:
        position = float_column(samples, "position")
        dwell = np.flatnonzero((station == stop_id) & ~np.isnan(position))
        if dwell.size:
            dwell = dwell[position[dwell] == position[dwell[0]]]
            c = body_to_ned(*np.radians(_stop_attitude(stop)))
            return int(dwell[dwell.size // 2]), c
    if np.sin(np.radians(stop["inc"])) < np.sin(np.radians(options.vertical_below)):
        raise ContinuousError(
            f"stop {int(stop_id)} is near vertical (inc {stop['inc']:.2f} deg): a three-axis "
            "run is tied there through the first frame position's toolface, and the samples "
            "carry no frame-position markers (column 'position')"
        )
    g = np.array([float_column(samples, f"acc_{a}")[boundary] for a in "xyz"])
    inc, toolface = inclination_toolface(g)
    return boundary, body_to_ned(np.radians(stop["azi"]), inc, toolface)


def _stop_attitude(stop: dict[str, float]) -> tuple[float, float, float]:
    """Azimuth, inclination and high-side toolface (deg) of a compassed stop. Where its
    azimuth is undefined (vertical: NaN) only their sum, the gyro toolface, is known, and
    at I ≈ 0 it alone fixes the attitude: A = Φ, ψ = 0."""
    if np.isnan(stop["azi"]):
        return stop["gyro_toolface"], stop["inc"], 0.0
    return stop["azi"], stop["inc"], stop["highside_toolface"]
