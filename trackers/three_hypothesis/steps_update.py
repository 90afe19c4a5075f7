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
from occbench.trackers.three_hypothesis.rules import Rules
from occbench.trackers.three_hypothesis.state import Branch, Memory, Person, Setting
from occbench.trackers.three_hypothesis.steps_output import add_node, add_nodes
from occbench.trackers.three_hypothesis.tentative import clear_measurements
from occbench.trackers.three_hypothesis.values import DepthOrder, Match, Matching, Measurements
from occbench.trackers.three_hypothesis.values import Occlusions, Predictions, Updated

log = logging.getLogger(__name__)


def update_matched(S: Predictions, V: Measurements, O: Occlusions, A: Matching, D: DepthOrder,
                   setting: Setting, memory: Memory) -> Updated:
    """UpdateAttributes(N_o^t) (3.3.3) of every matched person, in person order.

    M is corrected by the measurement (``rules.motion``; one behind others by
    ``rules.motion_behind``). A person absent from any occlusion takes the measurement's
    q and S (unless ``rules.covered`` puts its measurement behind a nearer one); one behind
    another keeps q and takes S from its prediction area (``rules.appearance_behind`` and
    ``rules.shape_behind``). A person matched through a hypothesis keeps its id and loses
    its other hypotheses; a tentative track is confirmed after ``confirm_frames`` matches
    (or sooner, by ``rules.confirm``), with the id ``rules.identity`` gives. Each gets a
    node in ``memory.graph``."""
    keys = sorted(A.matched)  # the matched persons, in person order
    if not keys:
        return Updated([], np.zeros((0, 4)), [], frozenset())
    matches = [A.matched[i] for i in keys]
    persons, p, in_front, rules = S.persons, V.p, D.in_front, setting.rules
    hidden = np.array([person.confirmed for person in persons], dtype=bool)
    hidden[keys] = False  # and unmatched at t
    confirmed = [persons[i].confirmed for i in keys]
    idx = np.array([m.node for m in matches])
    visible_dets = [m.det for m in matches]
    dbox = V.boxes[visible_dets]
    behind_r = [m.node in in_front for m in matches]
    behind = np.array(behind_r)
    z = box_measurements(dbox)
    own, partner = _own_share(S, V, O, rules, matches, hidden)
    Rs = rules.motion_front.noise(np.array([persons[i].R for i in keys]),
                                  np.where(behind, 1.0, own))
    predicted = S.Xp[idx], S.Pp[idx]
    Xc, Pc = rules.motion_behind.update(rules.motion.correct(*predicted, z, Rs), predicted,
                                        behind)  # x = x + K y, Joseph P
    estimate = state_boxes(Xc).tolist()
    tent = [m.det for r, m in enumerate(matches) if not confirmed[r]]
    empty = rules.support.empty(V.foreground, V.boxes[tent]) if tent else None
    # a detection on no foreground does not confirm a tentative track
    empty_dets = set() if empty is None else {d for d, e in zip(tent, empty.tolist()) if e}
    visible_share = _visible_share(V, A, D, matches, behind, dbox, setting)
    asked = [r for r, m in enumerate(matches) if m.det in tent and m.det not in empty_dets]
    clear = _clear(S, V, O, rules, [keys[r] for r in asked], [matches[r].det for r in asked])
    rules.line.record([persons[i] for i in keys], memory.t, dbox, S.Xp[idx], own,
                      _partner_centres(S, V, O, rules, matches, hidden, own))
    scores = V.scores.tolist()
    absorbed: set[int] = set()
    shares, partners = own.tolist(), partner.tolist()  # per-person reads as Python scalars
    covered = _covered(V, visible_dets, behind, setting)
    branches, shapes, occluders = [], [], []  # their nodes' columns (one add_nodes call)
    for r, (i, match) in enumerate(zip(keys, matches)):
        person, d, n = persons[i], match.det, match.node
        if not behind_r[r]:
            if not covered[r]:
                partner_q = persons[partners[r]].q if partners[r] >= 0 else None
                person.q = rules.appearance_front.update(person.q, p[d], shares[r], partner_q)
            shape = dbox[r]
        else:
            shape = rules.shape_behind.region(estimate[r], S.boxes[n])
            person.q = rules.appearance_behind.update(person.q, p[d], visible_share[r])
        person.merged = shares[r] < 1.0  # read by rules.split at t + 1
        if confirmed[r] or d not in empty_dets:
            person.hits += 1
        person.misses = 0
        person.spawned = False
        person.merged_still = None  # a new spell (rules.ending)
        rules.returning.record(person, match.rho)
        if not confirmed[r] and rules.confirm.confirms(
                person.hits, setting.life_cycle.confirm_frames, clear.get(d, False),
                scores[d]):
            _confirm(S, hidden, absorbed, person, shape, rules, memory)
        fronts = in_front.get(n, [])
        branch = Branch(VISIBLE, Xc[r], Pc[r], depth=len(fronts),
                        occluder=persons[fronts[0]].key if fronts else None)
        branches.append(branch)
        shapes.append(shape.tolist())
        occluders.append(memory.public.get(branch.occluder) if fronts else None)  # now
        person.shape = shape
        person.branches = [branch]
    add_nodes(memory, [persons[i] for i in keys], branches, shapes,
              [S.branches[m.node].node for m in matches], [m.stage for m in matches],
              [m.rho for m in matches], occluders)
    return Updated([persons[i] for i in keys], dbox, visible_dets, frozenset(absorbed))


def start_tracks(S: Predictions, V: Measurements, O: Occlusions, A: Matching,
                 setting: Setting, memory: Memory) -> list[Person]:
    """Each unmatched measurement starts a tentative track (3.3), confirmed in later
    frames (at once when ``confirm_frames`` is 1, or ``rules.confirm`` confirms one
    match); each gets a new key and a node in ``memory.graph``."""
    rules = setting.rules
    out: list[Person] = []
    new = A.unmatched.tolist()
    first = np.zeros(len(V.boxes), dtype=bool)
    first[A.first_stage()] = True
    parts = rules.parts.barred(V.boxes, first)  # a part of people measured: no track
    if parts is not None:
        new = [d for d in new if not parts[d]]
    empty = (rules.support.empty(V.foreground, V.boxes[new])
             if new and rules.confirm.uses_clear else None)
    clear_dets = [d for k, d in enumerate(new) if empty is None or not empty[k]]
    clear = _clear(S, V, O, rules, [-1] * len(clear_dets), clear_dets)  # -1: all are others
    for d in new:
        x0, P0, Q0, R0 = rules.motion.init(V.boxes[d])
        person = Person(memory.new_key(), V.p[d], Q0, R0, [Branch(VISIBLE, x0, P0)],
                        shape=V.boxes[d])
        if rules.confirm.confirms(1, setting.life_cycle.confirm_frames,
                                  clear.get(d, False), float(V.scores[d])):
            person.id = memory.new_id()
        person.branches[0].node = add_node(memory, person, person.branches[0], V.boxes[d],
                                           None, 0, float("nan"))
        out.append(person)
    return out


def _clear(S: Predictions, V: Measurements, O: Occlusions, rules: Rules, persons: list[int],
           dets: list[int]) -> dict[int, bool]:
    """Per measurement ``dets[k]`` of a matched tentative track (person index
    ``persons[k]``, -1: none), whether it is unambiguous (``tentative.clear_measurements``);
    only measured for a confirmation rule that reads it."""
    if not rules.confirm.uses_clear or not dets:
        return {}
    rows = np.array(dets)
    return dict(zip(rows.tolist(), clear_measurements(
        V.boxes, rows, O.delta, S.owners, np.array(persons)).tolist()))


def _covered(V: Measurements, dets: list[int], behind: np.ndarray,
             setting: Setting) -> list[bool]:
    """Per matched person (measured at rows ``dets`` of V), whether ``rules.covered`` puts
    its measurement behind a nearer one though eq. 3 puts it in front (``behind`` False);
    its q is then kept."""
    out = [False] * len(dets)
    if not setting.rules.covered.covers:  # the paper's rule: nothing to compute
        return out
    front = np.flatnonzero(~behind)
    if not len(front):
        return out
    kept = setting.rules.covered.behind(np.array(dets)[front], V.boxes,
                                        setting.occlusion.region_samples)
    for r, k in zip(front.tolist(), kept.tolist()):
        out[r] = k
    return out


def _visible_share(V: Measurements, A: Matching, D: DepthOrder, matches: list[Match],
                   behind: np.ndarray, visible: np.ndarray, setting: Setting) -> list[float]:
    """Per matched person (``matches``, measured at ``visible``), the share v of its
    measured region left visible by the matched people in front of it (1 - the largest
    share one of them covers; 1 for those not behind anyone), all pairs integrated in one
    ``region_overlaps`` call. Only computed for a rule that reads it."""
    share = [1.0] * len(matches)
    if not setting.rules.appearance_behind.uses_visible_share or not behind.any():
        return share
    k = behind.nonzero()[0]
    ia, ib = [], []  # (row among k, measurement of a matched person in front)
    for a, r in enumerate(k.tolist()):
        fronts = [A.matched[j].det for j in D.in_front[matches[r].node] if j in A.matched]
        ia += [a] * len(fronts)
        ib += fronts
    covered = covered_fraction(visible[k], V.boxes, setting.occlusion.region_samples,
                               (np.array(ia, dtype=np.int64), np.array(ib, dtype=np.int64)))
    for a, r in enumerate(k.tolist()):
        share[r] = 1.0 - float(covered[a])
    return share


def _own_share(S: Predictions, V: Measurements, O: Occlusions, rules: Rules,
               matches: list[Match], hidden: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per matched person (``matches``), the share of its measured region no
    hidden confirmed partner in O (``hidden``: (P,) bool, confirmed and unmatched at t)
    covers (``contact.own_shares``; 1 everywhere unless a front rule reads it), and the
    person index of the partner covering most (-1: none, or no rule reads it)."""
    partner = np.full(len(matches), -1)
    if not (rules.appearance_front.uses_shares or rules.motion_front.uses_shares
            or rules.split.uses_merged or rules.line.uses_shares):
        return np.ones(len(matches)), partner
    return own_shares(matches, O.pairs, S.owners, hidden, S.boxes, V.boxes, O.delta,
                      partner if rules.appearance_front.uses_partners else None), partner


def _partner_centres(S: Predictions, V: Measurements, O: Occlusions, rules: Rules,
                     matches: list[Match], hidden: np.ndarray, own: np.ndarray) -> np.ndarray:
    """(K, 2) centre of the predicted region (of the hidden partner in O covering most of
    each matched measurement, ``contact.own_shares``) that covers most of it; nan where
    none does or no rule reads it (``rules.line.uses_partners``)."""
    out = np.full((len(matches), 2), np.nan)
    if not rules.line.uses_partners or not (own < 1.0).any():
        return out
    partner = np.full(len(matches), -1)
    own_shares(matches, O.pairs, S.owners, hidden, S.boxes, V.boxes, O.delta, partner)
    for r in np.flatnonzero(partner >= 0).tolist():
        nodes, d = np.flatnonzero(S.owners == partner[r]), matches[r].det
        b = S.boxes[nodes]  # |S_m & S_d| = delta (|S_m| + |S_d|) / 2 (eq. 5)
        cover = O.delta[nodes][:, [d]].toarray().ravel() * (b[:, 2] * b[:, 3]
                                                             + V.boxes[d, 2] * V.boxes[d, 3])
        best = b[int(np.argmax(cover))]
        out[r] = best[0] + best[2] / 2, best[1] + best[3] / 2
    return out


def _confirm(S: Predictions, hidden: np.ndarray, absorbed: set[int], person: Person,
             shape: np.ndarray, rules: Rules, memory: Memory) -> None:
    """A tentative track reaches ``confirm_frames``: it takes a new id, or (by
    ``rules.identity``) the id of a hidden confirmed person, unmatched this frame and not
    yet ``absorbed``, one of whose hypotheses lies where it stands; that person joins
    ``absorbed`` (its hypotheses then end). ``hidden``: (P,) bool, the confirmed people
    unmatched at t (a confirmation within the frame only changes matched people)."""
    persons = S.persons
    candidate = hidden.copy()
    candidate[list(absorbed)] = False
    best = rules.identity.returning(shape, S.boxes, S.owners, candidate)
    if best is not None:
        person.id = persons[best].id
        absorbed.add(best)
        log.debug("tentative %d confirms hidden person %d", person.key, person.id)
    else:
        person.id = memory.new_id()
    memory.public[person.key] = person.id
