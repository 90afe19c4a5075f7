"""Who may start a target, and when: the multi-target life cycle (ours,
``life_cycle.min_hits``) or the paper's
single hand-initialised target (PBM 3), as small strategy objects.

PBM 3: "the target and its initial position were selected manually [...] the user just drew
a bounding box around the chosen target". ``GivenTargetOnly`` is that for the single-target
protocol (``occbench.pipeline.protocols``), whose only detection on the tracker's first frame
is the chosen person's box: the target started there is the only one, so no auto-started
target competes with it for candidates and none replaces it once it is lost.
``PBMTracker._start_targets`` asks ``may_start`` before each start; the other tests of a
start (``life_cycle``, ``rules.birth``) still apply.
"""

from __future__ import annotations


class AutoStarts:
    """Ours (a multi-target run has no hand initialisation; ``life_cycle.min_hits``): any free
    candidate passing the life cycle's tests starts a target, on any frame."""

    def may_start(self, frame: int, started: int) -> bool:
        """``frame``: 1-based count of frames seen; ``started``: targets started so far."""
        return True


class GivenTargetOnly:
    """PBM 3's hand initialisation: one target, started on the tracker's first frame (from
    the protocol's one detection there); no target starts later."""

    def may_start(self, frame: int, started: int) -> bool:
        """``frame``: 1-based count of frames seen; ``started``: targets started so far."""
        return frame == 1 and started == 0
