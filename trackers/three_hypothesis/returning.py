"""A hidden person's return: whether it is kept when every hypothesis is contradicted (Alg. 1
PruneHypothesis) and what appearance it needs to be matched again (3.3.2, mu_rho).

* ``EndContradicted`` (the paper) / ``HoldLast`` (``adaptations.hold_last``) /
  ``RestoreStill`` (``adaptations.restore_still``).

* ``AnyReturn`` (the paper): every pair with rho >= mu_rho may match, hidden or not.
* ``OwnReturn`` (``adaptations.own_return``): a confirmed person hidden at t - 1 may take a
  measurement only with rho (eq. 4) at least the lowest rho of its own last m matches (and
  mu_rho): its colours have varied that much while it was seen; a measurement further from
  them is someone else (issue 35: pets1-400 sil frame 156, a hidden person took an untracked
  passer-by's box at rho 0.48 after matches at 0.8-1.0).
* ``ReturnFloor`` (``adaptations.return_floor``): a confirmed person hidden at t - 1 may take a
  measurement only with rho at least one fixed floor, the same for everyone, on top of
  either rule above (issue 35: ecp1-180 sil 163, a hidden id took a newcomer at rho 0.43).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from occbench.trackers.three_hypothesis.hypotheses import STILL

if TYPE_CHECKING:
    from occbench.trackers.three_hypothesis.state import Branch, Person


@dataclass(frozen=True)
class EndContradicted:
    """Alg. 1 PruneHypothesis as written: a person with no hypothesis left ends."""

    def merged(self, person: Person, branch: Branch) -> None:
        return None

    def hold(self, person: Person, dropped: Branch | None) -> Branch | None:
        return None


@dataclass(frozen=True)
class HoldLast:
    """``hold_last``: a confirmed person whose last hypotheses were all contradicted (m
    frames in plain view) is kept, its first contradicted hypothesis standing where it is
    (velocity 0), unreported (``report_exposed``), until ``max_hidden``: a target kept
    unfound and found again through its gate (PBM's unfound targets; issue 35: pets1-400 sil
    person 13, undetected 166-212, ended at 209 and came back at 213 under a new id)."""

    def merged(self, person: Person, branch: Branch) -> None:
        return None

    def hold(self, person: Person, dropped: Branch | None) -> Branch | None:
        """The branch that keeps ``person``, or None (it ends)."""
        if dropped is None or not person.confirmed:
            return None
        dropped.x = dropped.x.copy()
        dropped.x[len(dropped.x) // 2:] = 0.0  # it stands (3.3.3 case 3's motion)
        return dropped


@dataclass(frozen=True)
class RestoreStill:
    """``restore_still``: hypothesis 3 (the person stays where it was last seen, Alg. 1) is
    dropped by ``merge_duplicates`` when it starts within half a pixel of another hypothesis
    (a person who stands or walks a few tenths of a pixel a frame), though nothing
    contradicted it. When every hypothesis kept is later contradicted (m frames in plain
    view, Alg. 1 PruneHypothesis), the person gets that hypothesis 3 back, once a hidden
    spell, at the place it was dropped with its exposure count at 0, and it is pruned as any
    hypothesis is. Issue 35: pets1-400 sil person 13, undetected 166-212 while he stood,
    ended at 209 when hypothesis 1 drifted off him and came back at 213 under a new id."""

    def merged(self, person: Person, branch: Branch) -> None:
        """``branch`` of ``person`` was dropped beside another hypothesis at its place."""
        if branch.kind == STILL and person.confirmed and person.merged_still is None:
            person.merged_still = branch

    def hold(self, person: Person, dropped: Branch | None) -> Branch | None:
        """The dropped hypothesis 3 (covariance and node of ``dropped``), or None."""
        still = person.merged_still
        if still is None or dropped is None or not person.confirmed:
            return None
        person.merged_still = None  # once a spell
        return replace(still, P=dropped.P, node=dropped.node, occluder=None, exposed=0,
                       covered=False, unseen=False, share=1.0, depth=0)


@dataclass(frozen=True)
class AnyReturn:
    """3.3.2 as written: mu_rho for every person."""

    def record(self, person: Person, rho: float) -> None:
        return None

    def floors(self, persons: list[Person], mu_rho: float) -> np.ndarray | None:
        return None


@dataclass(frozen=True)
class OwnReturn:
    """``own_return``: a hidden confirmed person's floor is the lowest rho of its last
    ``m`` matches (``LifeCycle.m``), never below mu_rho."""

    m: int

    def record(self, person: Person, rho: float) -> None:
        """Keep ``rho`` of ``person``'s match at t among its last m."""
        person.matched_rho = [*person.matched_rho[-(self.m - 1):], float(rho)]

    def floors(self, persons: list[Person], mu_rho: float) -> np.ndarray:
        """(P,) smallest rho each person may be matched with at t."""
        return np.array([max(mu_rho, min(p.matched_rho))
                         if p.confirmed and p.misses > 0 and p.matched_rho else mu_rho
                         for p in persons], dtype=float)


@dataclass(frozen=True)
class ReturnFloor:
    """``return_floor``: ``inner``'s floors, raised to ``floor`` for every confirmed person
    hidden at t - 1 (``misses`` > 0)."""

    floor: float
    inner: AnyReturn | OwnReturn

    def record(self, person: Person, rho: float) -> None:
        self.inner.record(person, rho)

    def floors(self, persons: list[Person], mu_rho: float) -> np.ndarray:
        """(P,) smallest rho each person may be matched with at t."""
        inner = self.inner.floors(persons, mu_rho)
        base = np.full(len(persons), mu_rho, dtype=float) if inner is None else inner
        hidden = np.array([p.confirmed and p.misses > 0 for p in persons], dtype=bool)
        return np.where(hidden, np.maximum(base, self.floor), base)


Returning = AnyReturn | OwnReturn | ReturnFloor


def returning_rule(own_return: bool, m: int, floor: float) -> Returning:
    """The rule of ``adaptations.own_return`` (m: ``LifeCycle.m``) and ``return_floor``."""
    inner = OwnReturn(m) if own_return else AnyReturn()
    return ReturnFloor(floor, inner) if floor > 0 else inner
