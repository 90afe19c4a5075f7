"""PBM: five-part model with layered data association (see ``trackers.layered.tracker``)."""

from trackers.layered.adaptations import Adaptations, StaleParts
from trackers.layered.evidence import HiddenEvidence
from trackers.layered.feature_models import FeatureModels, load_feature_models
from trackers.layered.params import (
    CandidateParams,
    FeatureParams,
    GateParams,
    LifeCycleParams,
    MatchParams,
    NoiseParams,
    PruneParams,
    ReportParams,
    SearchParams,
    UpdateParams,
)
from trackers.layered.starts import AutoStarts, GivenTargetOnly
from trackers.layered.tracker import PBMTracker

__all__ = ["Adaptations", "AutoStarts", "CandidateParams", "FeatureModels", "FeatureParams",
           "GateParams", "GivenTargetOnly", "HiddenEvidence", "LifeCycleParams", "MatchParams", "NoiseParams",
           "PBMTracker", "PruneParams", "ReportParams", "SearchParams", "StaleParts",
           "UpdateParams", "load_feature_models"]
