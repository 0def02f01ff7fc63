"""Position uncertainty: ISCWSA error-model propagation, gyro and MWD terms, error ellipses."""

from pipeline.uncertainty.ellipse import Ellipses, ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.gyro import GYRO_PRESETS, GyroTool, gyro_covariance, gyro_terms
from pipeline.uncertainty.model import StationJacobians, propagate, station_jacobians
from pipeline.uncertainty.mwd import MWD_PRESETS, MwdTool, mwd_covariance, mwd_terms
from pipeline.uncertainty.terms import Survey, Term, term_covariance

__all__ = [
    "GYRO_PRESETS",
    "MWD_PRESETS",
    "Ellipses",
    "GyroTool",
    "MwdTool",
    "StationJacobians",
    "Survey",
    "Term",
    "ellipses",
    "gyro_covariance",
    "gyro_terms",
    "horizontal_scale",
    "mwd_covariance",
    "mwd_terms",
    "propagate",
    "station_jacobians",
    "term_covariance",
    "vertical_scale",
]
