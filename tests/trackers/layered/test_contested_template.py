"""``adaptations.contested_template`` (``rules.TemplateContest``): a candidate several
targets may take goes to the target whose head template matches at its head best (PBM 4.1's
template, by column)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from occbench.trackers.layered import Adaptations
from occbench.trackers.layered.rules import NoContest, TemplateContest, build_rules


def _scene():
    """A textured frame; target 0's head template is a patch from elsewhere, target 1's is
    the patch at the candidate's head (x top-centre 44, y top 20, 8 px wide)."""
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (100, 100, 3), dtype=np.uint8)
    own = frame[20:28, 40:48].copy()
    other = frame[60:68, 70:78].copy()
    cand = SimpleNamespace(head=np.array([[44.0, 20.0, 8.0]]))
    return frame, cand, other, own


def _settle(rule, S, templates, misses):
    frame, cand, _, _ = _scene()
    tg = SimpleNamespace(head_template=templates, misses=np.array(misses))
    S = S.copy()
    rule.settle(S, cand, tg, frame, 0.25, 0.6)
    return S


def test_the_head_template_decides_who_takes_a_shared_candidate():
    # cav1-150 gt seed 1001, frame 38 (docs/generalisation.md): the neighbour scores the
    # detection 0.63, its own target (unfound 2 frames) 0.49
    _, _, other, own = _scene()
    S = np.array([[0.63], [0.49]])
    assert np.array_equal(_settle(NoContest(), S, [other, own], [0, 2]), S)
    settled = _settle(TemplateContest(1.5, 5), S, [other, own], [0, 2])
    assert settled[0, 0] == -np.inf and settled[1, 0] == 0.49  # the own target may take it
    # outside the margin (0.63 / 0.49 > 1.1) the candidate is not contested
    assert np.array_equal(_settle(TemplateContest(1.1, 5), S, [other, own], [0, 2]), S)
    # a stale template (unfound for more than prune_max_misses) does not compete
    assert np.array_equal(_settle(TemplateContest(1.5, 5), S, [other, own], [0, 6]), S)
    # no template matching well enough: nobody is struck
    assert np.array_equal(_settle(TemplateContest(1.5, 5), S, [other, other], [0, 2]), S)


def test_paper_mode_leaves_shared_candidates_to_the_assignment():
    assert isinstance(build_rules(Adaptations.paper()).contest, NoContest)
    assert isinstance(build_rules(Adaptations()).contest, NoContest)  # off until measured
    on = Adaptations(contested_template=1.5)
    assert isinstance(build_rules(on).contest, TemplateContest)
    assert set(on.changed()) - set(Adaptations().changed()) == {"contested_template"}
    assert Adaptations.paper().changed() == []
