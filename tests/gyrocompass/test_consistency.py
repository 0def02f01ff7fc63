"""The closed-form χ² survival function of the compass fit's consistency test against
scipy.stats (an independent implementation) and textbook quantiles."""

from __future__ import annotations

import math

import pytest
from scipy.stats import chi2

from pipeline.gyrocompass.consistency import chi2_sf


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 7, 12, 25, 60, 151])
def test_chi2_sf_matches_scipy(dof: int):
    for x in (1e-9, 1e-3, 0.5, 1.0, 3.0, dof / 2, dof, 2.0 * dof, 10.0 + 3 * dof, 400.0):
        assert chi2_sf(x, dof) == pytest.approx(chi2.sf(x, dof), rel=1e-11, abs=1e-300)


@pytest.mark.parametrize(("x", "dof"), [(3.841459, 1), (5.991465, 2), (11.0705, 5)])
def test_textbook_95_percent_quantiles(x: float, dof: int):
    assert chi2_sf(x, dof) == pytest.approx(0.05, abs=2e-6)


def test_edges():
    assert chi2_sf(0.0, 3) == 1.0
    assert chi2_sf(math.inf, 3) == 0.0
    assert math.isnan(chi2_sf(math.nan, 3))
    with pytest.raises(ValueError, match="degrees of freedom"):
        chi2_sf(1.0, 0)
