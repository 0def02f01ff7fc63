"""A trajectory's position uncertainty on points of its path (interpolated at MDs or TVDs).

The error model gives the covariance of survey stations. A point between two stations is not
one: its covariance depends on how the error terms act along the arc between them, and the
linear (or any) interpolation of the stations' covariances is not it. So a point at a
station's MD keeps that station's uncertainty columns exactly; a point between stations gets
NaN in each of them, flagged (:data:`INTERPOLATED_COLUMN`) and warned of by stage and columns —
never a plausible-looking invented σ. Covariances m², lengths m, azimuths deg.
"""

from __future__ import annotations

import warnings

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.errors import SurveyCheckWarning
from pipeline.uncertainty.carried import FLAG_COLUMN
from pipeline.uncertainty.stated import INTERPOLATED_COLUMN, WORDS
from pipeline.uncertainty.tieon import tie_on_of, with_tie_on

__all__ = ["INTERPOLATED_COLUMN", "uncertainty_on_points"]


def uncertainty_on_points(
    trajectory: pa.Table,
    points: pa.Table,
    above: NDArray[np.intp],
    at_station: NDArray[np.bool_],
    stage_id: str,
) -> pa.Table:
    """``points`` with ``trajectory``'s uncertainty columns (their field metadata: error
    model, confidence) and tie-on record, ``points`` itself where it has none. ``above[i]``
    is the trajectory row of the station at or above point ``i`` on its survey,
    ``at_station[i]`` whether the point is that station: it then keeps the station's values;
    otherwise they are NaN (``outside_validity``, where carried, is its upper station's: a
    point below a station outside the model's range is too) and ``interpolated`` is True,
    warned of naming ``stage_id`` and the columns."""
    names = [c for c in WORDS if c in trajectory.column_names]
    if not names:
        return points
    for name in names:
        values = trajectory.column(name).to_numpy(zero_copy_only=False).astype(np.float64)
        taken = np.where(at_station, values[above], np.nan)
        points = points.append_column(trajectory.schema.field(name), pa.array(taken))
    if FLAG_COLUMN in trajectory.column_names:
        flags = trajectory.column(FLAG_COLUMN).to_numpy(zero_copy_only=False).astype(bool)
        points = points.append_column(trajectory.schema.field(FLAG_COLUMN), pa.array(flags[above]))
    points = points.append_column(
        pa.field(INTERPOLATED_COLUMN, pa.bool_()), pa.array(~at_station, pa.bool_())
    )
    between = int((~at_station).sum())
    if between:
        warnings.warn(
            f"stage {stage_id!r}: {between} of {at_station.size} points lie between survey "
            f"stations; their {', '.join(names)} are NaN (flagged in column "
            f"{INTERPOLATED_COLUMN!r}): the error model gives the uncertainty of stations, and "
            "a point's between them is not an interpolation of theirs. The points at stations "
            "keep the stations' (include_stations: true).",
            SurveyCheckWarning,
            stacklevel=2,
        )
    record = tie_on_of(trajectory)
    return points if record is None else with_tie_on(points, record)
