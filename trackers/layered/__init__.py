"""PBM: five-part model with layered data association (see ``occbench.trackers.layered.tracker``)."""

from occbench.trackers.layered.adaptations import Adaptations, StaleParts
from occbench.trackers.layered.evidence import HiddenEvidence
from occbench.trackers.layered.feature_models import FeatureModels, load_feature_models
from occbench.trackers.layered.params import (
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
from occbench.trackers.layered.starts import AutoStarts, GivenTargetOnly
from occbench.trackers.layered.tracker import PBMTracker

__all__ = ["Adaptations", "AutoStarts", "CandidateParams", "FeatureModels", "FeatureParams",
           "GateParams", "GivenTargetOnly", "HiddenEvidence", "LifeCycleParams", "MatchParams", "NoiseParams",
           "PBMTracker", "PruneParams", "ReportParams", "SearchParams", "StaleParts",
           "UpdateParams", "load_feature_models"]
