"""Position uncertainty: ISCWSA error-model propagation of tool-model files, error ellipses."""

from pipeline.uncertainty.ellipse import (
    Ellipses,
    ellipses,
    hla_sigma,
    horizontal_scale,
    vertical_scale,
)
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
from pipeline.uncertainty.model import StationJacobians, propagate, station_jacobians
from pipeline.uncertainty.quantities import MissingSiteQuantity, ModelSite
from pipeline.uncertainty.terms import Survey, Term, term_covariance
from pipeline.uncertainty.toolmodel import ToolModel, ToolTerm, parse_tool_model, read_tool_model
from pipeline.uncertainty.weightfns import WEIGHT_FUNCTIONS

__all__ = [
    "MODELS_DIR",
    "SHIPPED",
    "WEIGHT_FUNCTIONS",
    "Ellipses",
    "MissingSiteQuantity",
    "ModelCatalogue",
    "ModelSite",
    "StationJacobians",
    "Survey",
    "Term",
    "ToolModel",
    "ToolTerm",
    "configure",
    "covariance",
    "ellipses",
    "find_model",
    "hla_sigma",
    "horizontal_scale",
    "model_files",
    "model_terms",
    "parse_tool_model",
    "propagate",
    "read_tool_model",
    "station_jacobians",
    "term_covariance",
    "term_covariances",
    "vertical_scale",
]
