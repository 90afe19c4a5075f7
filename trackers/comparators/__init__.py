"""PBM's comparators (Section 5): mean shift and a colour particle filter, with their loss
and restart rules."""

from occbench.trackers.comparators.loss import AnyDetection, MostSimilar, NeverLost, SimilarityBelow
from occbench.trackers.comparators.meanshift import MeanShiftTracker
from occbench.trackers.comparators.particle_filter import ColourParticleFilter

__all__ = ["AnyDetection", "ColourParticleFilter", "MeanShiftTracker", "MostSimilar", "NeverLost",
           "SimilarityBelow"]
