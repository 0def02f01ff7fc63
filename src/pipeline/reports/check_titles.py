"""How a report names each QC check for a client: a plain title and what its chart plots
(the check's internal name, an option of :class:`~pipeline.qc.options.QcOptions`, stays in
the run's tables and configuration), and units as printed (``deg/h`` → ``°/h``)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CheckTitle:
    """A check's chart title and the plotted quantity (``limit``: the check compares a
    non-negative value with a limit, so its band runs from 0)."""

    title: str
    plotted: str
    limit: bool = False


CHECK_TITLES: dict[str, CheckTitle] = {
    "earth_rate": CheckTitle("Earth rotation rate", "measured |ω| − Earth rate"),
    "gravity": CheckTitle("Gravity", "measured |g| − normal gravity"),
    "latitude": CheckTitle("Latitude from the sensors", "sensed − site latitude"),
    "horizontal_rate": CheckTitle("Horizontal Earth rate", "measured − Ω cos φ"),
    "rate_along_gravity": CheckTitle("Vertical Earth rate", "measured − (−Ω sin φ)"),
    "magnetic_field": CheckTitle("Magnetic field strength", "measured |B| − reference field"),
    "magnetic_dip": CheckTitle("Magnetic dip", "measured − reference dip"),
    "earth_rate_fit": CheckTitle("Earth rate fitted over the positions", "fitted − Ω cos φ"),
    "rest_gyro": CheckTitle("Tool at rest: gyros", "largest gyro-axis std. deviation", True),
    "rest_acc": CheckTitle(
        "Tool at rest: accelerometers", "largest accelerometer-axis std. deviation", True
    ),
    "recording_end": CheckTitle(
        "Frame position at the end of the recording",
        "averaging time short of the usual",
        True,
    ),
    "missing_positions": CheckTitle("Frame positions per station", "positions missing", True),
    "unread_stop": CheckTitle("Stop without a reading", "stops unread", True),
    "motion_rate": CheckTitle("Turn rate while moving", "largest |ω|", True),
    "motion_accel": CheckTitle("Shocks while moving", "largest ||a| − g₀|", True),
    "gyro_saturation": CheckTitle("Gyro range", "largest |gyro axis|", True),
    "acc_saturation": CheckTitle("Accelerometer range", "largest |accelerometer axis|", True),
    "dls_limit": CheckTitle("Dogleg severity", "dogleg severity", True),
}
"""Check name → what a report calls it."""

PRINTED_UNITS = {"deg": "°", "deg/h": "°/h", "deg/s": "°/s", "m/s2": "m/s²", "deg/30m": "°/30 m"}
"""A table's unit string → how a report prints it (others as they are)."""


def check_title(name: str, plotted: str) -> CheckTitle:
    """What a report calls check ``name``; an unknown one (another plugin's) keeps its name
    (underscores as spaces) and ``plotted``."""
    return CHECK_TITLES.get(name, CheckTitle(name.replace("_", " ").capitalize(), plotted))


def printed_unit(unit: str) -> str:
    """``unit`` as a report prints it."""
    return PRINTED_UNITS.get(unit, unit)
