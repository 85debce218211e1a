"""Analyses of recordings (schema v1): the tools a hippocampus lab uses on rodent data.

Each analysis is a plain function of a recording (an ``xarray.Dataset``) returning
labelled xarray objects whose ``attrs`` say how they were made: a DataArray when the
result is one array of values (a rate map), a Dataset when it holds several named
measures (a score, its threshold, its p-value); each works on dask-backed
(lazy) recordings and never imports torch. Results plot themselves through the ``hp``
accessor (``maps.hp.plot()``), registered with the recording and analysis packages.
"""

from .. import _accessor  # noqa: F401  (registers the ``.hp`` xarray accessor)
from ._common import AnalysisWarning
from .classification_accuracy import classification_accuracy
from .context_cells import context_cells
from .correlation_dimension import correlation_dimension
from .decode_covariance import decode_covariance
from .decode_environment import decode_environment
from .head_direction_tuning import head_direction_tuning
from .intrinsic_dimension import intrinsic_dimension
from .localization_error import localization_error
from .map_scorecard import map_scorecard
from .place_field_stability import place_field_stability
from .ratemaps import ratemaps
from .remapping_similarity import remapping_similarity
from .spatial_information import spatial_information
from .spatial_selectivity import spatial_selectivity

# cell classes: place fields, grid, border, speed, conjunctive, classification
from .border_score import border_score
from .classify_cells import classify_cells
from .conjunctive_tuning import conjunctive_tuning
from .grid_score import grid_score, spatial_autocorrelation
from .place_fields import place_fields
from .speed_score import speed_score

__all__ = [
    "AnalysisWarning",
    "classification_accuracy",
    "context_cells",
    "correlation_dimension",
    "decode_covariance",
    "decode_environment",
    "head_direction_tuning",
    "intrinsic_dimension",
    "localization_error",
    "map_scorecard",
    "place_field_stability",
    "ratemaps",
    "remapping_similarity",
    "spatial_information",
    "spatial_selectivity",
    "place_fields",
    "spatial_autocorrelation",
    "grid_score",
    "border_score",
    "speed_score",
    "conjunctive_tuning",
    "classify_cells",
]
