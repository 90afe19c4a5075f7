"""PBM's comparators (Section 5): mean shift and a colour particle filter."""

from trackers.comparators.meanshift import MeanShiftTracker
from trackers.comparators.particle_filter import ColourParticleFilter

__all__ = ["ColourParticleFilter", "MeanShiftTracker"]
