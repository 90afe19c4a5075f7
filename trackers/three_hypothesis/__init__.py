"""Reta et al. 2015: three-hypothesis tracking graph with occlusion reasoning.

Modules: ``graph`` (G = <N, E>, nodes and edges, snapshot), ``occlusion`` (eq. 2, eq. 3),
``association`` (3.3.2 two-stage Hungarian), ``hypotheses`` (Alg. 1's three cases),
``features`` (eqs. 1, 4, 5 on ellipse regions: the definitions), ``appearance`` (eq. 1
histograms, fast path), ``motion`` (Kalman M), ``params`` (the constructor's parameter
groups), ``rules`` (the paper's rule and ours for each step an adaptation changes),
``tracker`` (``RetaTracker``: Alg. 1), its steps by the paper's parts in ``steps_predict``
(1-2), ``steps_occlusion`` (3-5), ``steps_update`` (6, 9), ``steps_hypotheses`` (7-8) and
``steps_output`` (graph nodes, tracks), each step a function returning a frozen value of
``values``, over the records of ``state`` (people, the tracker's memory between frames).
"""

from occbench.trackers.three_hypothesis.motion import MotionModel
from occbench.trackers.three_hypothesis.params import (
    Adaptations,
    Appearance,
    Association,
    LifeCycle,
    Occlusion,
)
from occbench.trackers.three_hypothesis.tracker import RetaTracker

__all__ = ["Adaptations", "Appearance", "Association", "LifeCycle", "MotionModel", "Occlusion",
           "RetaTracker"]
