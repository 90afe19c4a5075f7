"""Shared detection and segmentation front end (both paper trackers).

Frames flow: ``background`` (MOG2/KNN foreground, shadows dropped) -> ``morphology``
(open/close) -> ``blobs`` (connected components) -> a person detector (``detectors``:
foreground blobs, silhouette template, HOG). The trackers' own features live with them:
Reta's ellipse histograms, rho and delta in ``occbench.trackers.three_hypothesis.features``, PBM's
part features in ``occbench.trackers.layered.parts``.
``heads`` is the PBM 2.3 hair/skin head detector.
"""

from occbench.trackers.frontend.background import BackgroundModel, clean_mask
from occbench.trackers.frontend.blobs import Blob, blobs_from_mask

__all__ = ["BackgroundModel", "Blob", "blobs_from_mask", "clean_mask"]
