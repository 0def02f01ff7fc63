"""Which magnetometer axis is at fault, or whether the field itself is disturbed: the
diagnosis of failed |B| and dip checks (DOMAIN.md §3) over the whole survey.

A magnetometer bias b is fixed in the tool frame: the reading is ``m = B_b + b`` with the
Earth field B_b turning with the frame, so the |B| and dip errors it makes change from one
frame position to the next (axes x, y, across the tool) and from station to station with the
tool's attitude (every axis, z included). External interference — a field fixed in the Earth
frame at a depth, e.g. from casing or a nearby steel mass, or an error of the reference
model — adds the same vector to B in every frame position of a station: the positions agree
with each other, all off by the same |B| and dip.

Candidates, fitted to every evaluated |B| and dip reading of the survey, residuals in units
of their tolerance (``e = (measured − reference)/tolerance``):

- ``mag x|y|z``: a bias b on that axis, constant over the survey (1 parameter, Gauss–Newton).
  Its σ has two parts: the scatter of the fitted residuals, ``s²/ΣJ²`` (s² = Σe²/(n − 1),
  J = ∂e/∂b), and the tool's accelerometer errors, which the scatter does not show because
  they are the same at every reading — the dip is measured against the accelerometers'
  down, so their bias b_a, misalignment and scale factor (``δa = b_a + G a``, each term of
  b_a and G independent with the tool's 1σ magnitude) move the fitted b by
  ``∂b/∂θ = −Σ J·∂e/∂θ / ΣJ²`` per term θ, as the compass σ carries them;
  ``σ_b² = s²/ΣJ² + Σ_θ (σ_θ ∂b/∂θ)²``;
- ``reference``: the same |B| and dip offsets at every reading (2 parameters: a reference
  field that is wrong, or a field fixed in the Earth frame over the whole survey);
- per station, ``interference``: that station's own |B| and dip offsets (its positions agree).

An axis is named when its fit leaves every reading within tolerance and explains the data
better than the other axes and the ``reference`` offsets by ``isolation_margin`` (Σe²); if the
``reference`` offsets fit as well (stations too alike in attitude), the result is
``undetermined``. When no axis fits, each failing station whose positions agree is
``interference``; otherwise ``undetermined``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.systematic import ToolErrors
from pipeline.qc.faults import Finding
from pipeline.qc.reference import EarthReference
from pipeline.qc.sensors import Sensors
from pipeline.qc.vector_checks import MAGNETIC_NOTE, VECTOR_CHECKS, IntArray, Rows, norm

CHECKS = ("magnetic_field", "magnetic_dip")
ITERATIONS = 6
"""Gauss–Newton iterations of an axis bias (the residuals are nearly linear in it)."""
STEP = 1.0
"""nT, central-difference step of the bias."""
ACC_STEP = 1e-4
"""Central-difference step of an accelerometer error: m/s² (bias), 1 (gain, per unit)."""
NO_ACC_ERRORS = ToolErrors(
    g_sensitivity=0.0, acc_bias=0.0, acc_misalignment=0.0, acc_scale_factor=0.0
)
"""A tool whose accelerometers are exact: the σ of a bias is its scatter alone."""


def diagnose_magnetic(
    rows: list[Rows],
    station: IntArray,
    sensors: Sensors,
    earth: EarthReference,
    margin: float,
    tool: ToolErrors = NO_ACC_ERRORS,
) -> dict[int, Finding]:
    """Diagnose the failed magnetic checks of a survey (module docstring): fills ``suspect``
    and replaces the generic note in the detail of the failed |B| and dip rows; returns the
    finding of each station with a failed magnetic check. ``tool``: the 1σ accelerometer
    errors (bias m/s², misalignment mrad, scale factor ppm) in each axis bias's σ."""
    by_name = {r.check: r for r in rows if r.check in CHECKS}
    if len(by_name) < len(CHECKS) or sensors.mag is None or earth.magnetic is None:
        return {}
    field_rows, dip_rows = by_name["magnetic_field"], by_name["magnetic_dip"]
    failed = field_rows.failed | dip_rows.failed
    if not failed.any():
        return {}
    used = field_rows.evaluated & dip_rows.evaluated
    mag, acc = sensors.mag[used], sensors.acc[used]
    tol = np.stack([field_rows.tolerance[used], dip_rows.tolerance[used]], axis=-1)
    ref = np.array([earth.magnetic.total_field, earth.magnetic.dip])
    dip = VECTOR_CHECKS["magnetic_dip"].func

    def residuals(bias: FloatArray, acc_error: FloatArray | None = None) -> FloatArray:
        """(n, 2) residuals in tolerance units of the readings corrected by ``bias`` (3,, nT)
        and, when given, by an accelerometer error ``acc_error`` (n, 3, m/s²)."""
        m = mag - bias
        a = acc if acc_error is None else acc - acc_error
        out: FloatArray = (np.stack([norm(m), dip(m, a)], axis=-1) - ref) / tol
        return out

    axes = [_axis_fit(residuals, j, _acc_errors(acc, tool)) for j in range(3)]
    offsets = residuals(np.zeros(3))
    reference = offsets - offsets.mean(axis=0)
    findings = _verdicts(axes, reference, offsets, tol, station[used], station[failed], margin)
    for r in (field_rows, dip_rows):
        for i in np.flatnonzero(r.failed):
            finding = findings[int(station[i])]
            r.suspect[i] = finding.suspect
            r.detail[i] = str(r.detail[i]).replace(MAGNETIC_NOTE, finding.diagnosis)
    return findings


def _acc_errors(acc: FloatArray, tool: ToolErrors) -> list[tuple[float, FloatArray]]:
    """Each accelerometer error term as (1σ, its δa (n, 3) per unit): the bias of each
    axis (m/s²), the misalignment of axis i towards j (rad) and the scale factor of each
    axis, ``δa_i = G_ij a_j``; terms of zero magnitude left out."""
    terms = []
    for i in range(3):
        unit = np.zeros_like(acc)
        unit[:, i] = 1.0
        terms.append((tool.acc_bias, unit))
        for j in range(3):
            gain = np.zeros_like(acc)
            gain[:, i] = acc[:, j]
            sigma = tool.acc_scale_factor * 1e-6 if i == j else tool.acc_misalignment * 1e-3
            terms.append((sigma, gain))
    return [(sigma, delta) for sigma, delta in terms if sigma > 0]


def _axis_fit(
    residuals: Callable[[FloatArray, FloatArray | None], FloatArray],
    j: int,
    acc_errors: list[tuple[float, FloatArray]],
) -> tuple[float, float, FloatArray]:
    """Bias (nT) of axis ``j`` minimising Σe², its σ (nT: the scatter's and that of the
    accelerometer errors ``acc_errors``, module docstring) and the fitted residuals."""
    unit = np.eye(3)[j]

    def slope(b: float) -> FloatArray:
        d = residuals((b + STEP) * unit, None) - residuals((b - STEP) * unit, None)
        out: FloatArray = d.ravel() / (2 * STEP)
        return out

    b = 0.0
    for _ in range(ITERATIONS):
        jac = slope(b)
        b -= float(jac @ residuals(b * unit, None).ravel() / (jac @ jac))
    r = residuals(b * unit, None)
    jac = slope(b)
    s2 = float(np.sum(r * r)) / max(r.size - 1, 1)
    var = s2 / float(jac @ jac)
    for sigma, delta in acc_errors:
        step = ACC_STEP * delta
        d = (residuals(b * unit, step) - residuals(b * unit, -step)).ravel() / (2 * ACC_STEP)
        var += (sigma * float(jac @ d) / float(jac @ jac)) ** 2
    return b, float(np.sqrt(var)), r


def _verdicts(
    axes: list[tuple[float, float, FloatArray]],
    reference: FloatArray,
    offsets: FloatArray,
    tol: FloatArray,
    station: IntArray,
    failing: IntArray,
    margin: float,
) -> dict[int, Finding]:
    """The finding of every failing station from the survey-wide fits."""
    scores = [float(np.sum(r * r)) for _, _, r in axes]
    fits = [float(np.max(np.abs(r))) <= 1.0 for _, _, r in axes]
    ref_score = float(np.sum(reference * reference))
    ref_fits = float(np.max(np.abs(reference))) <= 1.0
    order = np.argsort(scores)
    best = int(order[0])
    b, sigma, _ = axes[best]
    readings = len(station)
    stations = len(np.unique(station))
    estimate = (
        f"mag {'xyz'[best]}: bias ≈ {b:+.1f} ± {sigma:.2g} nT (1σ of the noise and the "
        "accelerometer errors), one bias fitted to the "
        f"|B| and dip of {readings} readings at {stations} stations"
    )
    if fits[best]:
        rivals = [
            f"mag {'xyz'[int(i)]}"
            for i in order[1:]
            if fits[i] and scores[i] - scores[best] < margin
        ]
        if ref_fits and ref_score - scores[best] < margin:
            rivals.append("a field offset fixed in the Earth frame (or a wrong reference)")
        if not rivals:
            finding = Finding(
                f"mag {'xyz'[best]}",
                f"{estimate}; it turns with the tool frame "
                + ("across the frame positions" if best < 2 else "from station to station")
                + ": a magnetometer bias, not interference",
            )
            return {int(s): finding for s in np.unique(failing)}
        undetermined = Finding(
            "undetermined",
            f"{estimate}, or {' or '.join(rivals)}: these explain the readings equally "
            "(the stations' attitudes are too alike to tell them apart)",
        )
        return {int(s): undetermined for s in np.unique(failing)}
    out = {}
    for s in np.unique(failing):
        own = offsets[station == s]
        spread = own - own.mean(axis=0)
        if own.size and float(np.max(np.abs(spread))) <= 1.0:
            d_field, d_dip = (own * tol[station == s]).mean(axis=0)
            out[int(s)] = Finding(
                "interference",
                f"every frame position sees the same offsets, |B| {d_field:+.0f} nT and dip "
                f"{d_dip:+.2f}°: a field fixed in the Earth frame — magnetic "
                "interference (casing, steel nearby) or a wrong reference — not a "
                f"magnetometer axis (no single axis bias fits the survey; best {estimate})",
            )
        else:
            out[int(s)] = Finding(
                "undetermined",
                "the frame positions disagree and no single magnetometer axis bias fits the "
                f"survey (best {estimate}): several faults, or interference changing with "
                "the position",
            )
    return out
