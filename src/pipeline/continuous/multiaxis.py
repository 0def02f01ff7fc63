"""Which gyro axes a continuous run uses, and the apsidal components of a two-axis gyro.

A tool's gyro axes are the ``gyro_*`` columns its samples carry (DOMAIN.md §2 body axes):
``x`` a single-axis gyro kept near the high side by the frame servo, ``xy`` two cross-axial
gyros (a dynamically tuned gyro; the tool may rotate freely or be servo'd), ``xyz`` a triad,
integrated as a strapdown attitude (:mod:`pipeline.continuous.strapdown`).

Two-axis tools (DOMAIN.md §5–6): rotating the transverse rates by the gravity toolface ψ of
frame x gives the high-side and right-side components whatever the tool's roll,

    h = ω_x cos ψ − ω_y sin ψ = Ω cos φ cos A cos I + Ω sin φ sin I − Ȧ sin I
    r = ω_x sin ψ + ω_y cos ψ = −Ω cos φ sin A + İ

(the Euler rates ``ω_nb^b = Rz(ψ)ᵀ Ry(I)ᵀ (0, 0, Ȧ) + Rz(ψ)ᵀ (0, İ, 0) + (0, 0, ψ̇)`` put
``−Ȧ sin I`` on the high side and ``İ`` on the right side; the roll rate ψ̇ and the axial
``Ȧ cos I`` stay on z). So Ȧ follows from h with no misalignment correction, and
``İ = r + Ω cos φ sin A`` is a direct (undifferentiated) inclination rate.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from pipeline.continuous.run import ContinuousError
from pipeline.earth.frames import FloatArray, sin_cos

GyroAxes = Literal["x", "xy", "xyz"]

__all__ = ["GyroAxes", "apsidal_components", "resolve_gyro_axes"]


def resolve_gyro_axes(columns: Sequence[str], wanted: str) -> GyroAxes:
    """The gyro axes to integrate: ``wanted`` (x, xy or xyz) if the samples have those
    ``gyro_*`` columns, or for ``auto`` the most the samples have (x, then xy, then xyz)."""
    present = "".join(a for a in "xyz" if f"gyro_{a}" in columns)
    if wanted == "auto":
        return "xyz" if present == "xyz" else "xy" if present.startswith("xy") else "x"
    if wanted not in ("x", "xy", "xyz"):
        raise ContinuousError(f"gyro_axes {wanted!r}: expected auto, x, xy or xyz")
    missing = [f"gyro_{a}" for a in wanted if a not in present]
    if missing:
        raise ContinuousError(
            f"gyro_axes {wanted!r}: the samples have no {', '.join(missing)} column "
            f"(gyro columns present: {', '.join(f'gyro_{a}' for a in present) or 'none'})"
        )
    axes: GyroAxes = "x" if wanted == "x" else "xy" if wanted == "xy" else "xyz"
    return axes


def apsidal_components(
    gyro_x: FloatArray, gyro_y: FloatArray, toolface: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """High-side and right-side rates (h, r) from the transverse gyros (any rate unit, same
    out) and the gravity toolface ψ of frame x (rad)."""
    sin_tf, cos_tf = sin_cos(toolface)
    high: FloatArray = gyro_x * cos_tf - gyro_y * sin_tf
    right: FloatArray = gyro_x * sin_tf + gyro_y * cos_tf
    return high, right
