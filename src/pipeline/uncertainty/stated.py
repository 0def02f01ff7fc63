"""What a position-uncertainty column states of itself, in its Arrow field metadata (as
units and north references travel, :mod:`pipeline.contracts`), so that every writer can say
it: the error model that made it (:data:`ERROR_MODEL_KEY`) and, for a column at a confidence
level, that level (:data:`CONFIDENCE_KEY`, the probability content) and how the 1σ size was
scaled to it (:data:`DIMENSIONS_KEY`: 2 for the horizontal ellipse, √χ²₂; 1 for the vertical
half-interval, the two-sided normal quantile; :mod:`pipeline.uncertainty.ellipse`); a
description (:data:`~pipeline.contracts.DESCRIPTION_KEY`) says all of it in words.

:func:`statement_of` gathers what a trajectory says of its uncertainty once, for the
deliverables that sum it up (the JSON summary, a DataFrame's ``attrs``, the report).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.contracts import DESCRIPTION_KEY
from pipeline.uncertainty.ellipse import ellipses
from pipeline.uncertainty.tieon import TieOn, TieOnRecord, tie_on_of, with_tie_on

INTERPOLATED_COLUMN = "interpolated"
"""Per row: a point between survey stations (True), not a station: its uncertainty columns
are NaN (the error model gives stations' σ, and a point's is no interpolation of theirs)."""

__all__ = [
    "CARRIED_KEY",
    "CONFIDENCE_KEY",
    "DIMENSIONS_KEY",
    "ERROR_MODEL_KEY",
    "FAMILIES",
    "INTERPOLATED_COLUMN",
    "Extent",
    "Family",
    "Statement",
    "file_statements",
    "interpolated_rows",
    "is_carried",
    "model_words",
    "statement_of",
    "unit_of",
    "with_statements",
]

CONFIDENCE_KEY = b"gyropipe.confidence"
"""Field metadata: the probability content of a column at a confidence level (``0.95``)."""
DIMENSIONS_KEY = b"gyropipe.confidence_dimensions"
"""Field metadata: the dimensions of that confidence region: ``2`` (an ellipse, χ² of 2 degrees
of freedom) or ``1`` (a two-sided interval of the normal distribution)."""
ERROR_MODEL_KEY = b"gyropipe.error_model"
"""Field metadata: the error model a column was computed with (``GYRO-NS rev 5``)."""
CARRIED_KEY = b"gyropipe.uncertainty_carried"
"""Field metadata: ``stations file``, a column carried from the stations file as it stated it,
not computed by the run that wrote it (:mod:`pipeline.uncertainty.carried`)."""

WORDS = {
    "cov_nn": "north variance",
    "cov_ne": "north-east covariance",
    "cov_nv": "north-vertical covariance",
    "cov_ee": "east variance",
    "cov_ev": "east-vertical covariance",
    "cov_vv": "vertical variance",
    "ellipse_major": "semi-major axis of the horizontal error ellipse, 1 sigma",
    "ellipse_minor": "semi-minor axis of the horizontal error ellipse, 1 sigma",
    "ellipse_azimuth": "azimuth of the error ellipse's semi-major axis",
    "sigma_v": "vertical error, 1 sigma",
    "ellipse_major_conf": "semi-major axis of the horizontal error ellipse",
    "ellipse_minor_conf": "semi-minor axis of the horizontal error ellipse",
    "vertical_conf": "vertical error half-interval",
}
"""The uncertainty columns, each described in words (ASCII: a LAS file's descriptions)."""


def unit_of(name: str) -> str:
    """The unit an uncertainty column (:data:`WORDS`) is in: m² for the covariances, deg for
    ``ellipse_azimuth``, m for the sizes."""
    return "m2" if name.startswith("cov_") else "deg" if name == "ellipse_azimuth" else "m"


AT_CONFIDENCE = {"ellipse_major_conf": 2, "ellipse_minor_conf": 2, "vertical_conf": 1}
"""The columns at the confidence level, by the dimensions of their region."""
REGION = {2: "2-D, chi-square of 2 dof", 1: "1-D, two-sided normal"}


@dataclass(frozen=True)
class Family:
    """Uncertainty columns of one σ convention: ``scale`` ``1 sigma squared`` (variances
    and covariances, m²), ``1 sigma`` (m, deg) or ``confidence`` (m, at the confidence
    level, the region :data:`REGION` of ``dimensions``)."""

    name: str
    columns: tuple[str, ...]
    scale: str
    dimensions: int | None = None


FAMILIES = (
    Family("covariance", tuple(c for c in WORDS if c.startswith("cov_")), "1 sigma squared"),
    Family("ellipse", ("ellipse_major", "ellipse_minor", "ellipse_azimuth", "sigma_v"), "1 sigma"),
    Family("ellipse_conf", ("ellipse_major_conf", "ellipse_minor_conf"), "confidence", 2),
    Family("vertical_conf", ("vertical_conf",), "confidence", 1),
)
"""The uncertainty columns (:data:`WORDS`) by σ convention (``ellipse_azimuth``, a direction,
goes with the 1σ axes it orients)."""


@dataclass(frozen=True)
class Extent:
    """The horizontal error ellipse's semi-major axis at one station: at 1σ and at the
    confidence level (m; None: no σ there, outside the error model's range, or no such
    column)."""

    md: float
    survey: str | None
    semi_major: float | None
    semi_major_conf: float | None


@dataclass(frozen=True)
class Statement:
    """What a trajectory says of its position uncertainty: the error model and confidence
    its columns state (None: not stated), the σ convention of each family of columns it
    has, the station of the largest horizontal semi-major axis (None: no station has a σ)
    and the deepest station's (TD), how many stations have no σ (NaN), and where each
    survey's σ starts (:class:`~pipeline.uncertainty.tieon.TieOn`)."""

    error_model: str | None
    confidence: float | None
    families: tuple[Family, ...]
    largest: Extent | None
    at_td: Extent
    without_sigma: int
    tie_on: tuple[TieOn, ...] = ()
    """each survey's tie-on and whether its uncertainty is in the σ (none recorded: empty)"""
    from_stations_file: bool = False
    """the columns are the stations file's, carried as it stated them (False: computed)"""
    interpolated_points: int = 0
    """rows between survey stations (:data:`INTERPOLATED_COLUMN`): no σ, and not stations"""

    def source_words(self) -> str:
        """Where the uncertainty comes from, in words, where the stations file stated it
        ('': computed by the run)."""
        if not self.from_stations_file:
            return ""
        return (
            "The position uncertainty is the one the stations file states, carried with its "
            "stations; it was not computed in this processing."
        )

    def as_dict(self) -> dict[str, object]:
        """The statement as JSON values (the JSON summary's ``uncertainty`` object)."""
        return {
            "error_model": self.error_model,
            "confidence": self.confidence,
            "columns": [
                {
                    "family": f.name,
                    "columns": list(f.columns),
                    "scale": f.scale,
                    "region": REGION[f.dimensions] if f.dimensions else None,
                }
                for f in self.families
            ],
            "largest": None if self.largest is None else vars(self.largest).copy(),
            "at_td": vars(self.at_td).copy(),
            "stations_without_sigma": self.without_sigma,
            "tie_on": [t.model_dump(mode="json") for t in self.tie_on],
            "from_stations_file": self.from_stations_file,
            "interpolated_points": self.interpolated_points,
        }


def statement_of(table: pa.Table) -> Statement | None:
    """:class:`Statement` of a trajectory with uncertainty columns (``md`` and
    ``ellipse_major``, or the horizontal covariances whose ellipse it is; None without them
    or rows). Rows flagged :data:`INTERPOLATED_COLUMN` are points between stations, not
    stations: counted apart, never the largest, TD or a station without σ (None: no row is
    a station). TD: the station of the largest MD (the last of equal ones). ``ValueError``
    where columns state different models or confidences."""
    names = set(table.column_names)
    horizontal = {"cov_nn", "cov_ne", "cov_ee"}
    if "md" not in names or not ({"ellipse_major"} <= names or horizontal <= names):
        return None
    if table.num_rows == 0:
        return None

    def values(name: str) -> NDArray[np.float64]:
        found: NDArray[np.float64] = table.column(name).to_numpy(zero_copy_only=False)
        return found.astype(np.float64)

    stated = file_statements(pa.schema([f for f in table.schema if f.name in WORDS]))
    md = values("md")
    if "ellipse_major" in names:
        major = values("ellipse_major")
    else:  # covariances alone (a WITSML matrixCov); no size where one is not finite
        nn, ne, ee = (values(c) for c in ("cov_nn", "cov_ne", "cov_ee"))
        finite = np.isfinite(nn) & np.isfinite(ne) & np.isfinite(ee)
        nn, ne, ee = (np.where(finite, v, np.nan) for v in (nn, ne, ee))
        major = ellipses(nn, ne, ee, np.zeros_like(nn)).semi_major
    conf = values("ellipse_major_conf") if "ellipse_major_conf" in names else None
    surveys = table.column("survey").to_pylist() if "survey" in names else None

    def extent(row: int) -> Extent:
        return Extent(
            md=float(md[row]),
            survey=None if surveys is None else surveys[row],
            semi_major=_defined(major[row]),
            semi_major_conf=None if conf is None else _defined(conf[row]),
        )

    station = ~interpolated_rows(table)
    if not station.any():
        return None
    sized = np.isfinite(major) & station
    deepest = len(md) - 1 - int(np.argmax(np.where(station, md, -np.inf)[::-1]))
    return Statement(
        error_model=stated.get("error_model"),
        confidence=float(stated["confidence"]) if "confidence" in stated else None,
        families=tuple(
            Family(f.name, present, f.scale, f.dimensions)
            for f in FAMILIES
            if (present := tuple(c for c in f.columns if c in names))
        ),
        largest=extent(int(np.argmax(np.where(sized, major, -np.inf)))) if sized.any() else None,
        at_td=extent(deepest),
        without_sigma=int((station & ~sized).sum()),
        tie_on=() if (ties := tie_on_of(table)) is None else ties.surveys,
        from_stations_file=is_carried(table),
        interpolated_points=int((~station).sum()),
    )


def interpolated_rows(table: pa.Table) -> NDArray[np.bool_]:
    """Per row, whether :data:`INTERPOLATED_COLUMN` flags it a point between survey
    stations (all False without the column; a null is a station)."""
    if INTERPOLATED_COLUMN not in table.column_names:
        return np.zeros(table.num_rows, np.bool_)
    flags = table.column(INTERPOLATED_COLUMN).fill_null(False)
    return np.asarray(flags.to_numpy(zero_copy_only=False), np.bool_)


def is_carried(table: pa.Table) -> bool:
    """Whether a trajectory's uncertainty columns were carried from its stations file (False:
    computed by the run that wrote them, or no such columns)."""
    return any(f.name in WORDS and CARRIED_KEY in (f.metadata or {}) for f in table.schema)


def _defined(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def model_words(name: str, revision: str) -> str:
    """An error model as stated: its name and revision (``GYRO-NS rev 5``)."""
    return f"{name} rev {revision}" if revision else name


def with_statements(
    table: pa.Table,
    confidence: float | None,
    model: str | None,
    tie_on: TieOnRecord | None = None,
) -> pa.Table:
    """``table`` with its uncertainty columns (:data:`WORDS`) stating ``model``
    (:func:`model_words`), those at a confidence level also ``confidence`` (probability,
    0-1) and their dimensions, and a description of each saying so (None: not stated, left
    as it is); with ``tie_on`` recorded (:func:`~pipeline.uncertainty.tieon.with_tie_on`),
    the descriptions also name each tie-on whose uncertainty is not included (a LAS
    file's curve descriptions then say it)."""
    if tie_on is not None:
        table = with_tie_on(table, tie_on)
    missing = [t for t in (tie_on.surveys if tie_on else ()) if t.missing()]
    since = "".join(
        f"; from the tie-on at {t.md:.2f} m MD"
        + (f" of survey {t.survey}" if t.survey is not None else "")
        + ", its own uncertainty not included"
        for t in missing
    )
    fields = []
    for f in table.schema:
        words = WORDS.get(f.name)
        if words is None:
            fields.append(f)
            continue
        meta = dict(f.metadata or {})
        if model is not None:
            meta[ERROR_MODEL_KEY] = model.encode()
        if (dims := AT_CONFIDENCE.get(f.name)) is not None and confidence is not None:
            meta[CONFIDENCE_KEY] = repr(confidence).encode()
            meta[DIMENSIONS_KEY] = str(dims).encode()
            words += f" at {confidence * 100:g} % confidence ({REGION[dims]})"
        if model is not None:
            words += f"; error model {model}"
        meta[DESCRIPTION_KEY] = (words + since).encode()
        fields.append(f.with_metadata(meta))
    return pa.Table.from_arrays(table.columns, schema=pa.schema(fields, table.schema.metadata))


def file_statements(schema: pa.Schema) -> dict[str, str]:
    """What a file of ``schema`` states once for all its columns: ``confidence`` and
    ``error_model`` where its columns state them (empty where none does); ``ValueError``
    where they state different ones (one file, as one north reference, holds one)."""
    stated: dict[str, str] = {}
    for name, key in (("confidence", CONFIDENCE_KEY), ("error_model", ERROR_MODEL_KEY)):
        values = sorted({f.metadata[key].decode() for f in schema if key in (f.metadata or {})})
        if len(values) > 1:
            raise ValueError(f"columns state different {name.replace('_', ' ')}s {values}")
        if values:
            stated[name] = values[0]
    return stated
