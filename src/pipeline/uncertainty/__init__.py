"""Position uncertainty: ISCWSA error-model propagation, gyro and MWD terms, error ellipses."""

from pipeline.uncertainty.ellipse import Ellipses, ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.engine import (
    MODELS_DIR,
    SHIPPED,
    ModelCatalogue,
    configure,
    covariance,
    find_model,
    model_files,
    model_terms,
    term_covariances,
)
from pipeline.uncertainty.gyro import GYRO_PRESETS, GyroTool, gyro_covariance, gyro_terms
from pipeline.uncertainty.model import StationJacobians, propagate, station_jacobians
from pipeline.uncertainty.mwd import MWD_PRESETS, MwdTool, mwd_covariance, mwd_terms
from pipeline.uncertainty.quantities import MissingSiteQuantity, ModelSite
from pipeline.uncertainty.terms import Survey, Term, term_covariance
from pipeline.uncertainty.toolmodel import ToolModel, ToolTerm, parse_tool_model, read_tool_model
from pipeline.uncertainty.weightfns import WEIGHT_FUNCTIONS

__all__ = [
    "GYRO_PRESETS",
    "MODELS_DIR",
    "MWD_PRESETS",
    "SHIPPED",
    "WEIGHT_FUNCTIONS",
    "Ellipses",
    "GyroTool",
    "MissingSiteQuantity",
    "ModelCatalogue",
    "ModelSite",
    "MwdTool",
    "StationJacobians",
    "Survey",
    "Term",
    "ToolModel",
    "ToolTerm",
    "configure",
    "covariance",
    "ellipses",
    "find_model",
    "gyro_covariance",
    "gyro_terms",
    "horizontal_scale",
    "model_files",
    "model_terms",
    "mwd_covariance",
    "mwd_terms",
    "parse_tool_model",
    "propagate",
    "read_tool_model",
    "station_jacobians",
    "term_covariance",
    "term_covariances",
    "vertical_scale",
]
