"""What every flag a survey station can carry means, in words for the client: the
continuous-mode bit flags, the gyrocompassing flags, and the QC checks that can fail.

A flag is either a failed QC check (the station failed: its listing row is highlighted) or a
caveat of the processing (the station passed, but a value is qualified: the values it
applies to and the QC cell are highlighted). The QC section explains each flag once.
"""

from __future__ import annotations

from dataclasses import dataclass

from pipeline.continuous.tables import (
    FLAG_AFTER_VERTICAL,
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_LARGE_MISALIGNMENT,
    FLAG_NAMES,
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
    FLAG_SHORT_STOP,
)

AZI, SIGMA_AZI = "azi", "sigma_azi"
"""Listing columns a flag can apply to (besides the QC column)."""


@dataclass(frozen=True)
class Flag:
    """One kind of flag: as printed in the QC column, what it means (one sentence: what,
    why it fired, whether it matters), the listing columns it applies to, and whether it
    is a failed check."""

    label: str
    meaning: str
    columns: tuple[str, ...] = ()
    failed: bool = False


CONTINUOUS: dict[int, Flag] = {
    FLAG_NEAR_VERTICAL: Flag(
        FLAG_NAMES[FLAG_NEAR_VERTICAL],
        "the inclination was below the near-vertical limit, where a gyro cannot sense a "
        "change of azimuth, so the azimuth was held constant through the section and has no "
        "defined σ; at such inclinations the azimuth hardly moves the position.",
        (AZI, SIGMA_AZI),
    ),
    FLAG_AFTER_VERTICAL: Flag(
        FLAG_NAMES[FLAG_AFTER_VERTICAL],
        "the azimuth was integrated on from a section where it was held near vertical; a "
        "change of azimuth inside that section is not measured (an end-stop closure takes "
        "it up as if it were gyro drift), so these azimuths rest on that change being small.",
        (AZI,),
    ),
    FLAG_LARGE_MISALIGNMENT: Flag(
        FLAG_NAMES[FLAG_LARGE_MISALIGNMENT],
        "the gyro's sensitive axis was turned further from the high side than the allowed "
        "misalignment, where the azimuth rate cannot be resolved, so the azimuth was held "
        "through those samples; compare it with its neighbours before relying on it.",
        (AZI,),
    ),
    FLAG_NO_CLOSURE: Flag(
        FLAG_NAMES[FLAG_NO_CLOSURE],
        "the run was integrated from one stop only (it started near vertical, where a stop "
        "gives no azimuth, or compassing rejected its end stop), so its azimuth drift was not "
        "removed by an end-stop closure; "
        "azimuths and positions carry the drift's uncertainty.",
    ),
    FLAG_AZIMUTH_UNDEFINED: Flag(
        FLAG_NAMES[FLAG_AZIMUTH_UNDEFINED],
        "near vertical the three-axis tool's attitude is integrated straight through, but "
        "the azimuth (the horizontal direction of the tool axis) is ill-conditioned, its "
        "error growing as 1/sin I; at such inclinations it hardly moves the position.",
        (AZI, SIGMA_AZI),
    ),
    FLAG_SHORT_STOP: Flag(
        FLAG_NAMES[FLAG_SHORT_STOP],
        "a compassing stop this run's azimuth is tied to was read from fewer frame positions "
        "than the survey's others (the recording ended, or positions were too short to "
        "average): the stop's azimuth, and the closure of the run on it, rest on less data, "
        "and the azimuths carry its larger uncertainty.",
        (AZI,),
    ),
}
"""Continuous-mode bit flags."""

COMPASS: dict[str, Flag] = {
    "azimuth_from_toolface": Flag(
        "azimuth from toolface",
        "near vertical the azimuth was not gyrocompassed from the tool axis but taken as the "
        "gyro toolface less the gravity toolface; it is as good as the two toolfaces, and at "
        "such inclinations it hardly moves the position.",
        (AZI,),
    ),
    "azimuth_undefined": Flag(
        "azimuth undefined",
        "the hole was vertical within what the accelerometers can resolve, so no horizontal "
        "direction of the tool axis exists and no azimuth is given; at such inclinations the "
        "azimuth does not move the position, and the trajectory takes the next surveyed "
        "azimuth.",
        (AZI, SIGMA_AZI),
    ),
    "poor_azimuth": Flag(
        "poor azimuth",
        "the azimuth's σ is above the acceptance limit or undefined; do not rely on this "
        "azimuth without a check survey.",
        (AZI, SIGMA_AZI),
    ),
    "frame_mismatch": Flag(
        "frame mismatch",
        "the frame positions seen by the accelerometers disagree with the commanded "
        "positions beyond tolerance: the tool may have turned between readings, so the "
        "multi-position azimuth is suspect.",
        (AZI,),
    ),
    "bias_not_removed": Flag(
        "bias not removed",
        "only one frame position was read, so the gyro biases could not be separated from "
        "the Earth's rotation and remain in the azimuth.",
        (AZI,),
    ),
    "fewer_positions": Flag(
        "fewer frame positions",
        "the azimuth was solved from fewer frame positions than the survey's other stations "
        "(the recording ended, or positions were too short to average): the gyro bias and "
        "drift were separated from fewer readings than at its neighbours, so this azimuth "
        "rests on a different, weaker set of positions; with no more readings than unknowns "
        "they cannot be checked against each other.",
        (AZI, SIGMA_AZI),
    ),
    "inconsistent": Flag(
        "inconsistent readings",
        "the readings at the frame positions disagree with each other more than their noise "
        "allows (χ² test): the tool may have moved or the gyro drifted during the station, "
        "and σ AZI then understates the azimuth's error.",
        (AZI, SIGMA_AZI),
    ),
}
"""Flags of gyrocompassed stations."""

CHECKS: dict[str, str] = {
    "earth_rate": "the magnitude of the measured rotation differs from the Earth's rate "
    "beyond tolerance: a gyro fault, or the tool was not at rest.",
    "gravity": "the magnitude of the measured acceleration differs from normal gravity at the "
    "site beyond tolerance: an accelerometer fault, or the tool was moving.",
    "latitude": "the latitude found from the gyros and accelerometers differs from the site's: "
    "a sensor error that biases the gyrocompassed azimuth.",
    "horizontal_rate": "the horizontal part of the measured rotation differs from the Earth's "
    "horizontal rate: the gyro error that biases gyrocompassing most directly.",
    "rate_along_gravity": "the rotation measured along gravity differs from the Earth's "
    "vertical rate: a gyro error or a misalignment between gyros and accelerometers.",
    "magnetic_field": "the total magnetic field differs from the reference field beyond "
    "tolerance: magnetic interference (casing, nearby wells) or a magnetometer fault.",
    "magnetic_dip": "the magnetic dip differs from the reference dip beyond tolerance: "
    "magnetic interference or a magnetometer fault.",
    "earth_rate_fit": "the horizontal Earth rate fitted through the frame positions differs "
    "from the site's: a gyro scale-factor or frame-position fault that biases the azimuth.",
    "rest_gyro": "the gyro readings scattered more than the limit during the station: the "
    "tool was not at rest.",
    "rest_acc": "the accelerometer readings scattered more than the limit during the "
    "station: the tool was not at rest.",
    "recording_end": "the recording ended while the tool was still reading this station's "
    "last frame position (the logger stopped, or the file was cut short): that position was "
    "averaged over less time than the survey's others, or not at all when too little was "
    "left, so the station rests on less data than its neighbours.",
    "missing_positions": "the station has fewer frame positions than the survey's other "
    "stations (the recording ended before its last positions, or they were too short to "
    "average): its azimuth rests on a different, weaker set of positions.",
    "unread_stop": "the tool stopped here (its depth held) but no frame position was held "
    "long and steadily enough to be averaged — the stop was too short, or the frame or the "
    "tool was still moving or vibrating: the station has no reading, so it is in neither the "
    "listing nor the trajectory.",
    "motion_rate": "while moving, the tool turned faster than the limit: a spin or a shock.",
    "motion_accel": "while moving, the tool accelerated more than the limit: shocks or jerks.",
    "gyro_saturation": "a gyro reading reached the sensor's full scale: those data are clipped.",
    "acc_saturation": "an accelerometer reading reached the sensor's full scale: those data "
    "are clipped.",
    "dls_limit": "the dogleg severity exceeds the limit set for the survey.",
    "in/out": "the in-run and out-run readings at this depth differ by more than the "
    "tolerance: drift not fully removed, or the tool's depth or orientation differed. The "
    "listed station is not corrected for the difference (the Method section says which run "
    "it comes from): check it before use.",
}
"""QC checks (validity checks, survey checks, in-run/out-run comparison): what a failure
means."""


def continuous_flags(bits: int) -> list[Flag]:
    """The flags of a continuous-mode station's bit field, in bit order."""
    return [flag for bit, flag in CONTINUOUS.items() if bits & bit]


def compass_flag(name: str) -> Flag:
    """A gyrocompassing flag by name; an unknown one (from another tool's processing)
    printed as it is."""
    return COMPASS.get(
        name,
        Flag(name, "a flag set by the processing of the tool's data; no explanation is known."),
    )


LABELS: dict[str, str] = {
    "recording_end": "cut short by end of recording",
    "missing_positions": "frame positions missing",
    "unread_stop": "stop not read",
}
"""How the listing labels the failure of a check that is no measurement (others: the
check's name and "failed")."""


def failed_check(name: str) -> Flag:
    """The failure of QC check ``name``."""
    meaning = CHECKS.get(name, f"the check {name!r} found a value beyond its limit.")
    return Flag(LABELS.get(name, f"{name} failed"), meaning, failed=True)


def long_course(max_course: float) -> Flag:
    """A station at the end of a course longer than ``max_course`` m (a first course after
    the tie-in, or a gap in the survey)."""
    return Flag(
        "long course",
        f"the course from the previous station (or from the tie-in) is longer than "
        f"{max_course:g} m: the hole between was not surveyed, and minimum curvature takes it "
        "as one circular arc, so the positions from here on rest on that assumption; check "
        "for missing stations.",
        ("md",),
    )


NOT_COMPARED = Flag(
    "read once",
    "the station was read in one run only (the in-run's deepest station, where the tool "
    "turned, or a station the other run did not stop at), so no in-run/out-run comparison "
    "checks it: its drift-corrected reading rests on the correction alone.",
)
"""A free gyro's station with no in-run/out-run pair."""

POSITION_MISMATCH = Flag(
    "position ≠ file",
    "the position the stations file lists for this station (its TVD, north, east) differs "
    "from the one recomputed from the file's MD, inclination and azimuth by more than the "
    "tolerance stated in the method: an angle or depth differs from the one the positions "
    "were computed with, or they rest on another tie-in or north reference; resolve it "
    "before using either.",
    ("tvd", "north", "east"),
    failed=True,
)
"""The check of a stations file's own positions against the recomputed ones failed."""
