"""Which sensor is at fault (seed 002's next step): at a station whose checks fail, try a
correction of one sensor at a time and keep the one that restores consistency.

The data of a station are its N readings at rest (frame positions). Every check on gyros and
accelerometers becomes an equation per reading, its residual in units of the check's
tolerance, ``e = (measured − reference) / tolerance`` (|ω|, |g|, latitude, ω_h, ω·g/|g|:
redundant on purpose, so that "consistent" means "every check passes"). Candidates, each
fitted by Gauss–Newton to minimise Σe² over the station:

- gyro x/y/z: a bias b (°/h, ``ω_j − b``) or a scale error s (ppm, ``ω_j / (1 + s)``);
- acc x/y/z: a bias (m/s²) or a scale error (ppm), likewise;
- triads: a rotation δ (mrad) of the gyro triad relative to the accelerometer triad (exact,
  norm-preserving), which changes only the angle between ω and g.

A candidate *restores consistency* when every corrected residual is within tolerance
(|e| ≤ 1). The best sensor (its better model) is named when it restores consistency and
explains the data better than every other sensor by at least ``margin`` (Σe² units);
otherwise the result is ``undetermined``, with why:

- one frame position gives few independent equations (two gyro quantities, ω_v and ω_h,
  and |g|): two axes often fit them equally;
- a bias and a scale error on an axis whose reading does not change between positions
  (the tool axis z, as the frame turns about it) cannot be told apart — the axis still is;
- a triad rotation is observable at rest only as the angle between ω and g: *which* triad
  is misaligned cannot be told, only by how much;
- nothing single restores consistency (several faults, motion, a wrong reference).

Gyro candidates need a three-axis gyro; single-axis and XY tools get accelerometer
candidates only (their gyro check fits and removes biases and cannot name an axis).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray

BoolArray = NDArray[np.bool_]
Correction = Callable[[FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]
"""(ω, g, p) → corrected (ω, g); ω, g of shape (S, N, 3), parameters p (S, P)."""

MAX_SCALE = 0.1
"""Largest scale error considered (10 %)."""
MAX_ROTATION = 0.35
"""Largest triad rotation considered, rad (20°)."""
ITERATIONS = 8
"""Gauss–Newton iterations (the residuals are nearly linear in every candidate's
parameters: two or three suffice)."""


@dataclass(frozen=True)
class Finding:
    """Result of fault isolation at one station: the suspected sensor ('gyro y', 'acc x'),
    'undetermined', or '' (nothing to isolate), and a sentence with the estimate."""

    suspect: str
    diagnosis: str


@dataclass(frozen=True)
class _Candidate:
    sensor: str
    params: int
    step: float
    """finite-difference step of the parameters"""
    limit: float
    """largest plausible |parameters|: a correction beyond it is not considered"""
    correct: Correction
    describe: Callable[[FloatArray], str]


def _bias(j: int, on_gyro: bool) -> Correction:
    e = np.eye(3)[j]

    def correct(w: FloatArray, g: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        shift = p[:, None, :1] * e
        return (w - shift, g) if on_gyro else (w, g - shift)

    return correct


def _scale(j: int, on_gyro: bool) -> Correction:
    axis = np.arange(3) == j

    def correct(w: FloatArray, g: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        factor = np.where(axis, 1.0 / (1.0 + p[:, None, :1]), 1.0)
        return (w * factor, g) if on_gyro else (w, g * factor)

    return correct


def _rotate(w: FloatArray, g: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rotate ω by −δ (rotation vector p, rad; Rodrigues), leaving g."""
    angle = np.linalg.norm(p, axis=-1)[:, None, None]
    axis = p[:, None, :] / np.where(angle > 0, angle, 1.0)
    cos, sin = np.cos(angle), np.sin(angle)
    along = np.einsum("sni,sni->sn", np.broadcast_to(axis, w.shape), w)[..., None] * axis
    return w * cos - np.cross(axis, w) * sin + along * (1 - cos), g


def _text(template: str, scale: float = 1.0) -> Callable[[FloatArray], str]:
    """Describe a one-parameter estimate: ``template`` formatted with parameter × scale."""
    return lambda p: template.format(p[0] * scale)


def candidates(gyro: bool) -> list[_Candidate]:
    """The single-sensor corrections tried (module docstring); gyro ones only for a
    three-axis gyro."""
    out = []
    triads = [("gyro", "°/h", 1e-3, "{:+.2f}")] if gyro else []
    triads.append(("acc", "m/s²", 1e-5, "{:+.4f}"))
    for j, axis in enumerate("xyz"):
        for name, unit, step, digits in triads:
            on_gyro = name == "gyro"
            out += [
                _Candidate(
                    sensor=f"{name} {axis}",
                    params=1,
                    step=step,
                    limit=np.inf,
                    correct=_bias(j, on_gyro),
                    describe=_text(f"bias ≈ {digits} {unit}"),
                ),
                _Candidate(
                    sensor=f"{name} {axis}",
                    params=1,
                    step=1e-6,
                    limit=MAX_SCALE,
                    correct=_scale(j, on_gyro),
                    describe=_text("scale ≈ {:+.0f} ppm", 1e6),
                ),
            ]
    if gyro:
        out.append(
            _Candidate(
                sensor="triads",
                params=3,
                step=1e-6,
                limit=MAX_ROTATION,
                correct=_rotate,
                describe=lambda p: f"rotated by ≈ {np.linalg.norm(p) * 1e3:.1f} mrad",
            )
        )
    return out


@dataclass(frozen=True)
class Equation:
    """A check as an isolation equation: ``func(ω, g)`` of readings (S, N, 3) → (S, N),
    its reference and the tolerance of every reading (S, N; inf: not used)."""

    gyro: bool
    """whether func reads the gyros (skipped without a three-axis gyro)"""
    func: Callable[[FloatArray, FloatArray], FloatArray]
    reference: float
    tolerance: FloatArray


def residuals(
    w: FloatArray | None, g: FloatArray, valid: BoolArray, equations: list[Equation]
) -> FloatArray:
    """(S, E·N) residuals of every equation and reading in units of their tolerance; zero
    for padding readings, an infinite tolerance, and gyro equations when ``w`` is None."""
    rates = np.full_like(g, np.nan) if w is None else w  # read by gyro equations only
    out = [
        np.where(valid, (eq.func(rates, g) - eq.reference) / eq.tolerance, 0.0)
        for eq in equations
        if w is not None or not eq.gyro
    ]
    return np.concatenate(out, axis=1)


def isolate(
    gyro: FloatArray | None,
    acc: FloatArray,
    valid: BoolArray,
    equations: list[Equation],
    margin: float = 1.0,
) -> list[Finding]:
    """Isolate the faulty sensor at S stations of up to N readings each.

    ``gyro`` (S, N, 3) °/h (None: no three-axis gyro) and ``acc`` (S, N, 3) m/s² are mean
    readings in the body frame; ``valid`` (S, N) marks real readings (the rest is padding);
    ``equations`` are the checks to satisfy; ``margin`` as in the module docstring."""
    w0 = np.zeros_like(acc) if gyro is None else gyro
    base = residuals(gyro, acc, valid, equations)
    tried = candidates(gyro is not None)
    fits = []
    for c in tried:

        def model(p: FloatArray, c: _Candidate = c) -> FloatArray:
            w, g = c.correct(w0, acc, p)
            return residuals(None if gyro is None else w, g, valid, equations)

        p = _gauss_newton(model, np.zeros((len(acc), c.params)), c.step, c.limit)
        r = model(p)
        plausible = np.linalg.norm(p, axis=1) < c.limit
        score = np.where(plausible, np.sum(r * r, axis=1), np.inf)
        fits.append((p, score, np.where(plausible, np.max(np.abs(r), axis=1), np.inf)))
    return [
        _decide(
            tried,
            [(f[0][s], float(f[1][s]), float(f[2][s])) for f in fits],
            float(np.max(np.abs(base[s]), initial=0.0)),
            margin,
        )
        for s in range(len(acc))
    ]


def _gauss_newton(
    model: Callable[[FloatArray], FloatArray], p: FloatArray, step: float, limit: float
) -> FloatArray:
    """Minimise Σ model(p)² per station (rows of p) by damped Gauss–Newton with a
    central-difference Jacobian, keeping each parameter within ±limit."""
    count = p.shape[1]
    eye = np.eye(count)
    for _ in range(ITERATIONS):
        r = model(p)
        jac = np.stack(
            [
                (model(p + step * eye[i]) - model(p - step * eye[i])) / (2 * step)
                for i in range(count)
            ],
            axis=-1,
        )
        normal = np.einsum("smi,smj->sij", jac, jac)
        damping = 1e-9 * (np.trace(normal, axis1=1, axis2=2) + 1.0)
        normal += damping[:, None, None] * eye
        p = p - np.linalg.solve(normal, np.einsum("smi,sm->si", jac, r)[..., None])[..., 0]
        p = np.clip(p, -limit, limit)
    return p


def _decide(
    tried: list[_Candidate],
    fits: list[tuple[FloatArray, float, float]],
    worst: float,
    margin: float,
) -> Finding:
    """The verdict at one station from each candidate's (parameters, Σe², max |e|)."""
    if worst <= 1.0:
        return Finding(
            "undetermined",
            "every isolation equation is within tolerance at these readings: nothing to "
            "correct, no sensor can be named",
        )
    best: dict[str, list[int]] = {}  # per sensor, its candidates from the best fit on
    for i in sorted(range(len(tried)), key=lambda i: fits[i][1]):
        best.setdefault(tried[i].sensor, []).append(i)
    first, *others = (models[0] for models in best.values())
    score, worst_left = fits[first][1], fits[first][2]
    if worst_left > 1.0:
        return Finding(
            "undetermined",
            f"no single-sensor correction restores consistency (best: {_say(tried, fits, first)}"
            f", leaving {worst_left:.1f} × tolerance): several faults, motion or a wrong "
            "reference?",
        )
    rivals = [i for i in others if fits[i][2] <= 1.0 and fits[i][1] - score < margin]
    sensor = tried[first].sensor
    if rivals or sensor == "triads":
        told = " or ".join(_say(tried, fits, i) for i in [first, *rivals])
        why = (
            "these explain the data equally (Σe² "
            + " vs ".join(f"{fits[i][1]:.2f}" for i in [first, *rivals])
            + "): this geometry cannot tell them apart"
            if rivals
            else "at rest only the relative orientation of the triads is observable, not "
            "which one moved"
        )
        return Finding("undetermined", f"{told}: {why}")
    text = _say(tried, fits, first)
    twins = [i for i in best[sensor][1:] if fits[i][2] <= 1.0 and fits[i][1] - score < margin]
    if twins:
        text += f" or {tried[twins[0]].describe(fits[twins[0]][0])} (not separable here)"
    return Finding(sensor, text)


def _say(tried: list[_Candidate], fits: list[tuple[FloatArray, float, float]], i: int) -> str:
    c = tried[i]
    if c.sensor == "triads":
        return f"gyro triad {c.describe(fits[i][0])} relative to the accelerometers"
    return f"{c.sensor}: {c.describe(fits[i][0])}"
