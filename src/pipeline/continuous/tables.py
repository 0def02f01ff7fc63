"""Contracts of the continuous-mode outputs and the bits of their ``flags`` column."""

from __future__ import annotations

from pipeline.contracts import TableContract, column
from pipeline.tables import Stations

FLAG_NEAR_VERTICAL = 1
"""Sample/station near vertical: azimuth held, not integrated."""
FLAG_AFTER_VERTICAL = 2
"""Azimuth integrated after a held near-vertical section (closure absorbs its change)."""
FLAG_LARGE_MISALIGNMENT = 4
"""Gyro more than ``max_misalignment`` from the high side: h is ill-conditioned."""
FLAG_NO_CLOSURE = 8
"""Integrated back from the end stop alone: the gyro bias is not removed by a closure."""
FLAG_AZIMUTH_UNDEFINED = 16
"""Near vertical on a three-axis tool: the attitude is integrated through (not held), but the
azimuth — the tool axis's horizontal direction — is ill-conditioned (error ∝ 1/sin I)."""

FLAG_SHORT_STOP = 32
"""Tied to a stop read from fewer frame positions than the survey's others (the recording
ended, positions too short): the azimuths (and a closure) rest on a stop of less data."""

FLAG_NAMES = {
    FLAG_NEAR_VERTICAL: "near vertical (azimuth held)",
    FLAG_AFTER_VERTICAL: "after a held section",
    FLAG_LARGE_MISALIGNMENT: "gyro far from high side",
    FLAG_NO_CLOSURE: "no closure",
    FLAG_AZIMUTH_UNDEFINED: "azimuth ill-defined (near vertical)",
    FLAG_SHORT_STOP: "tied to a stop with positions missing",
}


def describe_flags(flags: int) -> str:
    """The names of the bits set in ``flags``, joined by ``; `` (empty for 0)."""
    return "; ".join(name for bit, name in FLAG_NAMES.items() if flags & bit)


class ContinuousStations(Stations):
    """Stations of a continuous survey resampled at a fixed MD spacing (azimuth true north)."""

    time: float = column(unit="s", description="time at the station")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth, true north"
    )
    sigma_inc: float = column(
        unit="deg", ge=0, description="predicted σ of inc (accelerometers, odometer)"
    )
    sigma_azi: float = column(
        unit="deg", ge=0, finite=False, description="predicted σ of azi (stops, gyro)"
    )
    flags: int = column(unit=None, ge=0, description="bit flags (FLAG_* of the module)")


class ContinuousSeries(TableContract):
    """Full-rate series of the moving run (azimuth true north, closure applied)."""

    time: float = column(unit="s", monotonic="strict", description="time since the start")
    md: float = column(unit="m", description="odometer MD")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth, true north"
    )
    toolface: float = column(unit="deg", description="gravity toolface of frame x (δ), deg")
    flags: int = column(unit=None, ge=0, description="bit flags (FLAG_* of the module)")
