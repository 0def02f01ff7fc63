"""Position uncertainty: ISCWSA error-model propagation, gyro terms and error ellipses."""

from pipeline.uncertainty.ellipse import Ellipses, ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.gyro import (
    GYRO_PRESETS,
    GyroTool,
    Survey,
    Term,
    gyro_covariance,
    gyro_terms,
)
from pipeline.uncertainty.model import StationJacobians, propagate, station_jacobians

__all__ = [
    "GYRO_PRESETS",
    "Ellipses",
    "GyroTool",
    "StationJacobians",
    "Survey",
    "Term",
    "ellipses",
    "gyro_covariance",
    "gyro_terms",
    "horizontal_scale",
    "propagate",
    "station_jacobians",
    "vertical_scale",
]
