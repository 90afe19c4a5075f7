"""Alg. 1, steps 6 and 9 (Reta 3.3, 3.3.3): UpdateAttributes of the matched people, their
confirmation, and the tentative tracks the unmatched measurements start.
"""

from __future__ import annotations

import logging

import numpy as np

from occbench.trackers.three_hypothesis.contact import own_shares
from occbench.trackers.three_hypothesis.graph import VISIBLE
from occbench.trackers.three_hypothesis.motion import box_measurements, state_boxes
from occbench.trackers.three_hypothesis.occlusion import covered_fraction
from occbench.trackers.three_hypothesis.state import Branch, Person
from occbench.trackers.three_hypothesis.values import Frame
from occbench.trackers.three_hypothesis.tentative import clear_measurements

log = logging.getLogger(__name__)


class UpdateSteps:
    """``RetaTracker``'s steps 6 and 9 (a mixin: ``self`` is the tracker)."""

    def _update_matched(self, f: Frame) -> list[Person]:
        """UpdateAttributes(N_o^t) (3.3.3) of every matched person, in person order.

        M is corrected by the measurement (``rules.motion``; one behind others by
        ``rules.motion_behind``). A person absent from any occlusion takes the measurement's
        q and S; one behind another keeps q and takes S from its prediction area
        (``rules.appearance_behind`` and ``rules.shape_behind``). A person matched through a
        hypothesis keeps its id and loses its other hypotheses; a tentative track is
        confirmed after ``confirm_frames`` matches (or sooner, by ``rules.confirm``), with
        the id ``rules.identity`` gives."""
        rows = sorted(f.A.matched.items())
        f.visible = np.zeros((0, 4))
        if not rows:
            return []
        persons, dets, p, pred, in_front = f.S.persons, f.V.boxes, f.V.p, f.S.boxes, f.D.in_front
        rules = self.rules
        idx = np.array([m.node for _, m in rows])
        f.visible_dets = [m.det for _, m in rows]
        f.visible = dbox = dets[f.visible_dets]
        behind = np.array([m.node in in_front for _, m in rows])
        z = box_measurements(dbox)
        own = self._own_share(f, rows)
        Rs = rules.motion_front.noise(np.array([persons[i].R for i, _ in rows]),
                                      np.where(behind, 1.0, own))
        predicted = f.S.Xp[idx], f.S.Pp[idx]
        Xc, Pc = rules.motion_behind.update(rules.motion.correct(*predicted, z, Rs), predicted,
                                            behind)  # x = x + K y, Joseph P
        estimate = state_boxes(Xc).tolist()
        tent = [m.det for i, m in rows if not persons[i].confirmed]
        empty = rules.support.empty(f.V.foreground, dets[tent]) if tent else None
        # a detection on no foreground does not confirm a tentative track
        empty_dets = set() if empty is None else {d for d, e in zip(tent, empty.tolist()) if e}
        visible_share = self._visible_share(f, rows, behind)
        clear = self._clear(f, [(i, m.det) for i, m in rows
                                if m.det in tent and m.det not in empty_dets])
        for r, (i, match) in enumerate(rows):
            person, d, n = persons[i], match.det, match.node
            if not behind[r]:
                person.q = rules.appearance_front.update(person.q, p[d], own[r])
                shape = dbox[r]
            else:
                shape = rules.shape_behind.region(estimate[r], pred[n])
                person.q = rules.appearance_behind.update(person.q, p[d], visible_share[r])
            if person.confirmed or d not in empty_dets:
                person.hits += 1
            person.misses = 0
            rules.line.record(person, self._frame, dbox[r], f.S.Xp[n])
            person.spawned = False
            if not person.confirmed and rules.confirm.confirms(
                    person.hits, self.life_cycle.confirm_frames, clear.get(d, False),
                    float(f.V.scores[d])):
                self._confirm(f, person, shape)
            fronts = in_front.get(n, [])
            branch = Branch(VISIBLE, Xc[r], Pc[r], depth=len(fronts),
                             occluder=persons[fronts[0]].key if fronts else None)
            branch.node = self._add_node(person, branch, shape, f.S.branches[n].node,
                                          match.stage, match.rho)
            person.shape = shape
            person.branches = [branch]
        return [persons[i] for i in sorted(f.A.matched)]

    def _start_tracks(self, f: Frame) -> list[Person]:
        """Each unmatched measurement starts a tentative track (3.3), confirmed in later
        frames (at once when ``confirm_frames`` is 1, or ``rules.confirm`` confirms one
        match)."""
        out: list[Person] = []
        new = f.A.unmatched.tolist()
        first = np.zeros(len(f.V.boxes), dtype=bool)
        first[f.A.first_stage()] = True
        parts = self.rules.parts.barred(f.V.boxes, first)  # a part of people measured: no track
        if parts is not None:
            new = [d for d in new if not parts[d]]
        empty = (self.rules.support.empty(f.V.foreground, f.V.boxes[new])
                 if new and self.rules.confirm.uses_clear else None)
        clear = self._clear(f, [(-1, d) for k, d in enumerate(new)  # -1: all are others
                                if empty is None or not empty[k]])
        for d in new:
            x0, P0, Q0, R0 = self.rules.motion.init(f.V.boxes[d])
            person = Person(self._next_key, f.V.p[d], Q0, R0, [Branch(VISIBLE, x0, P0)],
                             shape=f.V.boxes[d])
            self._next_key += 1
            if self.rules.confirm.confirms(1, self.life_cycle.confirm_frames,
                                           clear.get(d, False), float(f.V.scores[d])):
                person.id = self._next_id
                self._next_id += 1
            person.branches[0].node = self._add_node(person, person.branches[0], f.V.boxes[d],
                                                     None, 0, float("nan"))
            out.append(person)
        return out

    def _clear(self, f: Frame, tentative: list[tuple[int, int]]) -> dict[int, bool]:
        """Per (person, measurement) pair of a matched tentative track, whether the
        measurement is unambiguous (``tentative.clear_measurements``); only measured for a
        confirmation rule that reads it."""
        if not self.rules.confirm.uses_clear or not tentative:
            return {}
        rows = np.array([d for _, d in tentative])
        return dict(zip(rows.tolist(), clear_measurements(
            f.V.boxes, rows, f.O.delta, f.S.owners, np.array([i for i, _ in tentative])).tolist()))

    def _visible_share(self, f: Frame, rows: list, behind: np.ndarray) -> list[float]:
        """Per matched row, the share v of its measured region left visible by the matched
        people in front of it (1 - the largest share one of them covers; 1 for rows not
        behind anyone), all pairs integrated in one ``region_overlaps`` call. Only
        computed for a rule that reads it."""
        share = [1.0] * len(rows)
        if not self.rules.appearance_behind.uses_visible_share or not behind.any():
            return share
        k = behind.nonzero()[0]
        ia, ib = [], []  # (row among k, measurement of a matched person in front)
        for a, r in enumerate(k.tolist()):
            fronts = [f.A.matched[j].det for j in f.D.in_front[rows[r][1].node]
                      if j in f.A.matched]
            ia += [a] * len(fronts)
            ib += fronts
        covered = covered_fraction(f.visible[k], f.V.boxes, self.occlusion.region_samples,
                                   (np.array(ia, dtype=np.int64), np.array(ib, dtype=np.int64)))
        for a, r in enumerate(k.tolist()):
            share[r] = 1.0 - float(covered[a])
        return share

    def _own_share(self, f: Frame, rows: list) -> np.ndarray:
        """Per matched row, the share of its measured region no hidden confirmed partner
        in O covers (``contact.own_shares``); 1 everywhere unless a front rule reads it."""
        if not (self.rules.appearance_front.uses_shares or self.rules.motion_front.uses_shares):
            return np.ones(len(rows))
        persons = f.S.persons
        hidden = np.array([person.confirmed and i not in f.A.matched and i not in f.absorbed
                           for i, person in enumerate(persons)], dtype=bool)
        return own_shares([(i, m.det, m.node) for i, m in rows], f.O.pairs, f.S.owners, hidden,
                          f.S.boxes, f.V.boxes, f.O.delta)

    def _confirm(self, f: Frame, person: Person, shape: np.ndarray) -> None:
        """A tentative track reaches ``confirm_frames``: it takes a new id, or (by
        ``rules.identity``) the id of a hidden confirmed person, unmatched this frame, one of
        whose hypotheses lies where it stands; that person's hypotheses then end."""
        persons = f.S.persons
        candidate = np.array([person.confirmed and i not in f.A.matched and i not in f.absorbed
                              for i, person in enumerate(persons)], dtype=bool)
        best = self.rules.identity.returning(shape, f.S.boxes, f.S.owners, candidate)
        if best is not None:
            person.id = persons[best].id
            f.absorbed.add(best)
            log.debug("tentative %d confirms hidden person %d", person.key, person.id)
        else:
            person.id = self._next_id
            self._next_id += 1
        self._public[person.key] = person.id
