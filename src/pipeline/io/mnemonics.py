"""Curve mnemonics: the canonical columns gyropipe reads, the names files give them, and the
physical quantity (hence canonical unit) of each.

Names are compared after :func:`normalise`: upper case, with everything that is not a
letter or digit removed, so ``+N/-S`` → ``NS``, ``Measured Depth`` → ``MEASUREDDEPTH``,
``GYRO_X`` → ``GYROX``. Extend the table for your files with :func:`register_alias`
(plugins do it at import time) or per file with a reader's ``columns`` option.

Deliberately absent: ambiguous short names such as ``AZ`` (azimuth or accelerometer z?) or
``TF`` without context, and ``NORTHING``/``EASTING``: the map coordinates in the CRS that
listings give beside ``+N/-S``/``+E/-W`` (as the well's ``northing``/``easting``), never
displacements from the wellhead. ``GX/GY/GZ`` are accelerometer (gravity) components, as in
the MWD convention; ``BX/BY/BZ`` magnetometers; gyro rates are ``WX/WY/WZ`` or ``GYRO X`` etc.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from pipeline.uncertainty.stated import WORDS

_NOT_ALNUM = re.compile(r"[^0-9A-Z]+")


@dataclass(frozen=True)
class Curve:
    """A canonical column: its name, physical quantity (a key of
    :data:`pipeline.units.QUANTITIES`, or None for counts and labels) and aliases."""

    name: str
    quantity: str | None
    aliases: tuple[str, ...]
    description: str


def normalise(text: str) -> str:
    """Comparison form of a column name or mnemonic (upper case, letters and digits)."""
    return _NOT_ALNUM.sub("", text.upper())


def _triad(prefix: str, quantity: str, what: str, stems: tuple[str, ...]) -> list[Curve]:
    return [
        Curve(
            f"{prefix}_{axis}",
            quantity,
            tuple(f"{stem}{axis.upper()}" for stem in stems)
            + tuple(f"{stem} {axis.upper()}" for stem in stems),
            f"{what} along body {axis}",
        )
        for axis in "xyz"
    ]


CURVES: dict[str, Curve] = {
    c.name: c
    for c in [
        Curve(
            "md",
            "length",
            ("MD", "DEPT", "DEPTH", "MEASURED DEPTH", "MEAS DEPTH", "DMEA"),
            "measured depth",
        ),
        Curve(
            "inc",
            "angle",
            ("INC", "INCL", "INCLINATION", "DEVI", "SDEV", "DEVIATION", "ZENITH", "ZENITH ANGLE"),
            "inclination from vertical",
        ),
        Curve(
            "azi",
            "angle",
            ("AZI", "AZIM", "AZIMUTH", "HAZI", "AZTN", "DIRECTION"),
            "azimuth clockwise from north",
        ),
        Curve("tvd", "length", ("TVD", "TRUE VERTICAL DEPTH"), "true vertical depth"),
        Curve(
            "north",
            "length",
            ("NORTH", "+N/-S", "N/S", "NS", "N-S", "DNS", "LAT DISP"),
            "displacement north (+) / south (-)",
        ),
        Curve(
            "east",
            "length",
            ("EAST", "+E/-W", "E/W", "EW", "E-W", "DEW", "DEP DISP"),
            "displacement east (+) / west (-)",
        ),
        Curve("dls", "dogleg_severity", ("DLS", "DOGLEG SEVERITY", "DOGLEG"), "dogleg severity"),
        Curve(
            "toolface",
            "angle",
            ("TOOLFACE", "TOOL FACE", "GTF", "RB", "RELATIVE BEARING", "HIGH SIDE TOOLFACE"),
            "gravity toolface",
        ),
        Curve(
            "time",
            "time",
            ("TIME", "TIM", "ETIM", "ELAPSED TIME"),
            "time since the start of the record",
        ),
        Curve(
            "frame_angle",
            "angle",
            ("FRAME ANGLE", "FRAME", "FANG", "ROTOR ANGLE"),
            "angle of the sensor frame relative to the housing",
        ),
        *_triad("gyro", "angular_rate", "angular rate", ("W", "GYRO", "GYR", "RATE", "OMEGA")),
        *_triad("acc", "acceleration", "acceleration", ("G", "ACC", "ACCEL")),
        *_triad("mag", "magnetic_field", "magnetic field", ("B", "MAG", "H")),
        Curve("t", "time", ("MID TIME", "DWELL TIME"), "mid-time of a frame position's dwell"),
        Curve("duration", "time", ("DURATION", "AVERAGING TIME"), "averaging time"),
        Curve("n", None, ("SAMPLES", "COUNT"), "samples averaged"),
        *[
            Curve(
                f"{triad}_{axis}_std",
                quantity,
                (f"{triad} {axis} std",),
                f"standard deviation of {triad}_{axis}",
            )
            for triad, quantity in (("gyro", "angular_rate"), ("acc", "acceleration"))
            for axis in "xyz"
        ],
        Curve("station", None, ("STATION", "STN", "STATION ID"), "station index"),
        Curve("position", None, ("POSITION", "POS", "FRAME POSITION"), "frame position index"),
        Curve("survey", None, ("SURVEY", "SURVEY ID"), "survey id"),
        Curve(
            "station_type",
            None,
            ("STATION TYPE", "STN TYPE", "SURVEY TYPE", "TYPE", "COMMENT", "COMMENTS", "REMARKS"),
            "station type, as the file names it (Tie-In, Projection to TD)",
        ),
        *[  # a trajectory's own uncertainty columns, by the names gyropipe writes
            Curve(
                name,
                "area" if name.startswith("cov_") else "angle" if "azimuth" in name else "length",
                (),
                words,
            )
            for name, words in WORDS.items()
        ],
    ]
}

_INDEX: dict[str, str] = {}


def register_alias(alias: str, canonical: str) -> None:
    """Teach the table that ``alias`` names the canonical column ``canonical``."""
    if canonical not in CURVES:
        raise KeyError(f"unknown canonical column {canonical!r} (known: {', '.join(CURVES)})")
    key = normalise(alias)
    other = _INDEX.get(key)
    if other is not None and other != canonical:
        raise ValueError(f"alias {alias!r} already names {other!r}")
    _INDEX[key] = canonical


for _curve in CURVES.values():
    for _alias in (_curve.name, *_curve.aliases):
        register_alias(_alias, _curve.name)


def canonical_name(name: str) -> str | None:
    """The canonical column a file's column name or mnemonic stands for, if known."""
    return _INDEX.get(normalise(name))
