"""PBM's comparators (Section 5): mean shift (fixed size and scale-adapting), a colour
particle filter and the connected-component mean-shift particle filter (CCMSPF), with their
loss and restart rules."""

from occbench.trackers.comparators.ccmspf import ConnectedComponentMeanShiftPF
from occbench.trackers.comparators.loss import AnyDetection, MostSimilar, NeverLost, SimilarityBelow
from occbench.trackers.comparators.meanshift import MeanShiftTracker, ScaleAdaptiveMeanShift
from occbench.trackers.comparators.particle_filter import ColourParticleFilter

__all__ = ["AnyDetection", "ColourParticleFilter", "ConnectedComponentMeanShiftPF",
           "MeanShiftTracker", "MostSimilar", "NeverLost", "ScaleAdaptiveMeanShift",
           "SimilarityBelow"]
