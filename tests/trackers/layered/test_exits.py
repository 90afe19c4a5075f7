"""``adaptations.border_exit``: an unfound target last matched occluded at an image border
has left (``exits.BorderExit``); off, only a predicted box beyond the border tells it."""

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered.adaptations import Adaptations
from occbench.trackers.layered.exits import BorderExit, PredictedExit
from occbench.trackers.layered.rules import build_rules


def _targets():
    """Four targets in a 320 x 240 image: at the top edge (y 0) occluded, at the top edge
    unoccluded, inside the image occluded, across the right edge occluded."""
    dof = np.array([[100.0, 0.0, 105.0, 10.0, 10.0, 30.0],
                    [150.0, 0.0, 155.0, 10.0, 10.0, 30.0],
                    [100.0, 100.0, 105.0, 110.0, 10.0, 30.0],
                    [312.0, 100.0, 317.0, 110.0, 10.0, 30.0]])
    return SimpleNamespace(dof=dof, occluded=np.array([True, False, True, True]))


def test_an_occluded_last_match_at_the_border_is_gone():
    assert BorderExit().gone(_targets(), 320, 240).tolist() == [True, False, False, True]
    assert PredictedExit().gone(_targets(), 320, 240) is None


def test_paper_keeps_the_predicted_exit_and_the_default_adds_the_border():
    assert isinstance(build_rules(Adaptations.paper()).exit, PredictedExit)
    assert isinstance(build_rules(Adaptations(border_exit=False)).exit, PredictedExit)
    assert isinstance(build_rules(Adaptations()).exit, BorderExit)  # the default
