"""PBM: five-part model with layered data association (see ``trackers.layered.tracker``)."""

from trackers.layered.models import FeatureModels, load_feature_models
from trackers.layered.tracker import PBMTracker

__all__ = ["FeatureModels", "PBMTracker", "load_feature_models"]
