"""The χ² test of a position fit without scipy.stats (which takes a second to import).

For an integer number of degrees of freedom ``k`` the survival function has a closed form
(Abramowitz & Stegun 26.4.4 and 26.4.5)::

    k even:  Q(χ²|k) = e^(−x) Σ_{i=0}^{k/2−1} x^i / i!
    k odd:   Q(χ²|k) = erfc(√x) + e^(−x) Σ_{i=1}^{(k−1)/2} x^(i−½) / Γ(i+½)

with ``x = χ²/2``; each term is summed in log space, so large χ² or ``k`` neither overflow
nor lose the small tail probabilities the test compares with.
"""

from __future__ import annotations

import math


def chi2_sf(chi2: float, dof: int) -> float:
    """P(X ≥ ``chi2``) for X ~ χ² with ``dof`` ≥ 1 degrees of freedom (dimensionless)."""
    if dof < 1:
        raise ValueError(f"degrees of freedom must be at least 1, got {dof}")
    if not chi2 > 0.0:
        return 1.0 if chi2 == chi2 else math.nan  # NaN in, NaN out
    x = chi2 / 2.0
    if math.isinf(x):
        return 0.0
    log_x = math.log(x)
    if dof % 2 == 0:
        powers = [float(i) for i in range(dof // 2)]
        head = 0.0
    else:
        powers = [i - 0.5 for i in range(1, (dof + 1) // 2)]
        head = math.erfc(math.sqrt(x))
    tail = math.fsum(math.exp(p * log_x - x - math.lgamma(p + 1.0)) for p in powers)
    return min(1.0, head + tail)
