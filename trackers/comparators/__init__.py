"""PBM's comparators (Section 5): mean shift and a colour particle filter, with their loss
and restart rules."""

from trackers.comparators.loss import AnyDetection, MostSimilar, NeverLost, SimilarityBelow
from trackers.comparators.meanshift import MeanShiftTracker
from trackers.comparators.particle_filter import ColourParticleFilter

__all__ = ["AnyDetection", "ColourParticleFilter", "MeanShiftTracker", "MostSimilar", "NeverLost",
           "SimilarityBelow"]
