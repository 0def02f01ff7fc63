"""The north an error model works in and the north a listing states. Every error model's
terms are referred to true north (a gyro's earth-rate terms by the azimuth from true north,
an MWD model's magnetic azimuth through the declination it is given), so a trajectory
listed in grid or magnetic north gives it true azimuths and takes its NEV covariance back
turned into its own north. Angles in degrees, east of true north positive; covariances m²
(N, E, V)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pipeline.earth.frames import FloatArray
from pipeline.errors import GyropipeError, MissingSiteError
from pipeline.survey.north import convert_azimuth, turned_covariance, wrap_360

__all__ = ["ListingNorth", "MissingNorthError", "listing_north", "turned_matrices"]

_CORRECTION = {
    "grid": (
        "grid_convergence",
        "grid convergence",
        "deg, grid north east of true north positive",
    ),
    "magnetic": (
        "declination",
        "magnetic declination",
        "deg, magnetic north east of true north positive",
    ),
}
"""North reference → the well field of its correction to true north, its name, its sign."""


class MissingNorthError(MissingSiteError):
    """A stage's error model works in true north and the listing's grid or magnetic
    azimuths come without the correction that refers them to it (``run``: the input whose
    azimuths, where the stage takes several)."""

    def __init__(
        self,
        stage: str,
        north: str,
        *,
        modelled: bool = False,
        python: bool = False,
        run: str | None = None,
    ) -> None:
        field, name, sign = _CORRECTION[north]
        self.stage, self.missing, self.param, self.north = stage, [field], None, north
        self.modelled, self.run = modelled, run
        model = (
            "; or its latitude, longitude and survey_date, for the geomagnetic model's"
            if modelled and north == "magnetic"
            else ""
        )
        where = (
            f"the function's `well={{\"{field}\": …}}` (or the input's well metadata)"
            if python
            else f"the pipeline's `well:` block, on the command line (--well {field}=…) or "
            "in the input file's header"
        )
        whose = f"{run}'s" if run else "the"
        GyropipeError.__init__(
            self,
            f"the {stage} stage needs the {name} of {whose} {north}-north azimuths (the error "
            f"models work in true north, their covariances turned back into {north} north): "
            f"give the well's `{field}` ({sign}) in {where}{model}",
        )

    def in_python(self) -> MissingSiteError:
        """The same error worded for the Python API (``well={…}``)."""
        return MissingNorthError(
            self.stage, self.north, modelled=self.modelled, python=True, run=self.run
        )


@dataclass(frozen=True)
class ListingNorth:
    """A listing's north reference and its azimuths' change to true north ``to_true``
    (δ, deg: A_true = A + δ)."""

    north: str
    to_true: float

    def true_azimuths(self, azi_deg: ArrayLike) -> FloatArray:
        """The listing's azimuths (deg) referred to true north, in [0, 360); NaN kept."""
        azi = np.asarray(azi_deg, dtype=np.float64)
        out: FloatArray = np.where(np.isnan(azi), np.nan, wrap_360(azi + self.to_true))
        return out

    def covariance(self, cov: np.ndarray) -> np.ndarray:
        """True-north NEV covariances (n, 3, 3), m², referred to the listing's north."""
        return turned_matrices(cov, -self.to_true)


def listing_north(
    north: str,
    *,
    stage: str,
    convergence_deg: float | None = None,
    declination_deg: float | None = None,
    modelled: bool = False,
) -> ListingNorth:
    """The listing's north with its correction to true north: γ (``convergence_deg``) of
    grid azimuths, D (``declination_deg``) of magnetic ones. Raises
    :class:`MissingNorthError` naming ``stage`` and how to give the one missing
    (``modelled``: the stage would take a declination from the geomagnetic model at the
    well's site)."""
    needed = {"grid": convergence_deg, "magnetic": declination_deg}
    if north in needed and needed[north] is None:
        raise MissingNorthError(stage, north, modelled=modelled)
    shift, _ = convert_azimuth(
        0.0, north, "true", convergence_deg=convergence_deg, declination_deg=declination_deg
    )
    to_true = float(shift)
    return ListingNorth(north, to_true - 360.0 if to_true > 180.0 else to_true)


def turned_matrices(cov: np.ndarray, shift_deg: ArrayLike) -> np.ndarray:
    """NEV covariances (n, 3, 3), m², referred to the north whose azimuths are A' = A + δ
    (``shift_deg``: scalar or per matrix; :func:`~pipeline.survey.north.turned_covariance`)."""
    nn, ne, nv, ee, ev, vv = turned_covariance(
        [cov[:, r, c] for r, c in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))], shift_deg
    )
    return np.stack(
        [np.stack([nn, ne, nv], -1), np.stack([ne, ee, ev], -1), np.stack([nv, ev, vv], -1)], -2
    )
