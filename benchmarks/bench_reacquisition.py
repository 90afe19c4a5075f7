"""Re-acquisitions and identity exchanges of trackers on a generalisation set, per seed.

A *re-acquisition* is a reported box of an id on a ground-truth person (IoU >= 0.5, one
Hungarian matching per frame) after that id was on no person for more than ``--gap``
frames; it is *wrong* when the person differs from the id's last one. An *exchange* is an
id on one person at frame t - 1 and on another at t. Prints, per tracker and seed and in
total, COMBINED IDF1 / HOTA / MOTA / IDs, wrong / all re-acquisitions and exchanges; with
``--events`` every wrong re-acquisition: frame, id, last and new person, frames unfound,
state, and the id that was on the new person before it (with how many frames before).

With ``--stacks``, pbm's (or any tracker's) *stacks*: two reported boxes at IoU >= 0.5 with
each other for >= 3 frames in a row. Under the CLEAR matching (``paper.match_rows``) a stack
frame is *two people* when the two boxes are matched to two different people, else *one
person*; a stack is counted by its majority. A *duplicate* is a one-person stack in which the
detection went to one and then to the other (found in turn) and never to both in one frame.
Prints the false positives and CLEAR ID switches (at a frame where one of the ids is in a
stack that frame or the one before) at one-person frames of stacks and in duplicates, and
the two-person stacks that are found in turn and never together (what the boxes and the
found states alone cannot tell from a duplicate); docs/adaptations.md, "stacked targets".

For choosing rules on tuning data only (docs/generalisation.md): the sets are those of
``harness.sweeps.generalisation`` but the seeds are yours (default 0-5); seeds of a set's untouched
list are refused unless ``--untouched`` is given.

    .venv/bin/python benchmarks/bench_reacquisition.py --set "crowd d0.8" --seeds 0 1 \\
        --trackers reta pbm "pbm_rm0=pbm:tracker.adaptations.relative_match=0"

A tracker is ``<config>`` or ``<label>=<config>[:<override>,<override>...]`` (Hydra
overrides of the composed config). Run it niced on a shared machine: ``nice -n 10``.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness.io.mot import MotTable  # noqa: E402
from harness.metrics import combine, score_sequence  # noqa: E402
from harness.metrics.paper import considered, match_rows  # noqa: E402
from harness.pipeline.build import build_source, build_tracker, load_sequences  # noqa: E402
from harness.pipeline.loop import frames  # noqa: E402
from harness.sweeps import generalisation as G  # noqa: E402
from trackers.geometry import iou_matrix  # noqa: E402


@dataclass
class Tally:
    """Counts of one tracker over the sequences of a run."""

    reacquired: int = 0
    wrong: int = 0
    exchanges: int = 0
    stacks: Counter = field(default_factory=Counter)  # ``stack_counts`` summed
    events: list[dict] = field(default_factory=list)
    scores: list = field(default_factory=list)

    def add(self, other: Tally) -> None:
        self.reacquired += other.reacquired
        self.wrong += other.wrong
        self.exchanges += other.exchanges
        self.stacks.update(other.stacks)
        self.events += other.events
        self.scores += other.scores


def parse_tracker(spec: str) -> tuple[str, str, list[str]]:
    """'label=config:o1,o2' | 'config' -> (label, config, overrides)."""
    head = spec.split(":", 1)[0]
    label, _, rest = spec.partition("=") if "=" in head else (head, "", spec)
    config, _, overrides = rest.partition(":")
    return label, config, [o for o in overrides.split(",") if o]


def set_overrides(name: str, seed: int, length: int | None) -> list[str]:
    s = {e.name: e for e in G.SETS}[name]
    out = G._resolve(s.overrides, G.trajectories_root()) + [f"seed={seed}", "progress=false"]
    if length:
        key = {"dataset=synthetic": "length", "dataset=replay": "max_frames"}
        out += [f"dataset.{key[o]}={length}" for o in out if o in key]
    return out


def run_seed(overrides: list[str], trackers: list[tuple[str, str, list[str]]], gap: int,
             stacks: bool = False) -> dict[str, Tally]:
    """Every tracker on every sequence of one composed run; the tallies per tracker."""
    cfg = G.compose(overrides)
    tallies = {label: Tally() for label, _, _ in trackers}
    for seq in load_sequences(cfg.dataset):
        built = {label: build_tracker(label, G.compose([*overrides, f"tracker={config}",
                                                        *extra]).tracker)
                 for label, config, extra in trackers}
        last = {label: {} for label in built}  # id -> (person, frame)
        holder = {label: {} for label in built}  # person -> (id, frame)
        rows = {label: ([], [], [], []) for label in built}
        gt = seq.gt.table
        for step in frames(seq, build_source(cfg.detector), str(cfg.get("foreground", "auto"))):
            k = step.index
            r = seq.gt.rows_of(k)
            r = r[gt.conf[r] > 0]
            gtb, gti = gt.boxes[r], gt.ids[r]
            for label, tracker in built.items():
                image = None if step.image is None else step.image.copy()
                tracks = [t for t in tracker.update(image, step.detections, step.foreground)
                          if t.state.reported]
                fr, ids, boxes, hidden = rows[label]
                for t in tracks:
                    fr.append(k)
                    ids.append(int(t.id))
                    boxes.append(np.asarray(t.box, dtype=np.float64))
                    hidden.append(t.state.name == "OCCLUDED")
                if not tracks or not len(gtb):
                    continue
                iou = iou_matrix(np.array([t.box for t in tracks]), gtb)
                tally = tallies[label]
                for a, b in zip(*linear_sum_assignment(-iou)):
                    if iou[a, b] < 0.5:
                        continue
                    i, g = int(tracks[a].id), int(gti[b])
                    if i in last[label]:
                        was, seen = last[label][i]
                        unfound = k - seen - 1
                        tally.exchanges += unfound == 0 and was != g
                        if unfound > gap:
                            tally.reacquired += 1
                            tally.wrong += was != g
                            if was != g:
                                before = holder[label].get(g)
                                tally.events.append(dict(
                                    sequence=seq.info.name, frame=k, id=i, was=was, now=g,
                                    unfound=unfound, state=tracks[a].state.name,
                                    before=None if before is None else (before[0], k - before[1])))
                    last[label][i] = (g, k)
                    holder[label][g] = (i, k)
        for label, (fr, ids, boxes, hidden) in rows.items():
            n = len(fr)
            fr, ids = np.asarray(fr, dtype=np.int64), np.asarray(ids, dtype=np.int64)
            order = np.lexsort((ids, fr))  # MOT order: by frame, then id
            table = MotTable(fr[order], ids[order], np.asarray(boxes).reshape(n, 4)[order],
                             np.ones(n), np.full(n, -1, dtype=np.int64), np.full(n, np.nan))
            tallies[label].scores.append(score_sequence(gt, table))
            if stacks:
                tallies[label].stacks.update(
                    stack_counts(gt, table, np.asarray(hidden, dtype=bool)[order]))
    return tallies


def stack_counts(gt: MotTable, res: MotTable, hidden: np.ndarray, frames: int = 3
                 ) -> dict[str, int]:
    """Stacks of a result table (module docstring); ``hidden`` (len(res),) bool: OCCLUDED."""
    gt = considered(gt)
    m = match_rows(gt, res)
    person = np.full(len(res), -1)
    person[m[m >= 0]] = gt.ids[m >= 0]
    runs: dict[tuple[int, int], list[tuple[int, int, int]]] = {}  # (id, id) -> [(frame, row, row)]
    for f, rr in res.frame_index().items():
        rr = rr[np.argsort(res.ids[rr])]
        for x, y in zip(*np.nonzero(np.triu(iou_matrix(res.boxes[rr], res.boxes[rr]) >= 0.5, 1))):
            runs.setdefault((int(res.ids[rr[x]]), int(res.ids[rr[y]])), []).append(
                (f, rr[x], rr[y]))
    one: set[tuple[int, int]] = set()  # (frame, id) in a one-person stack frame
    dup: set[tuple[int, int]] = set()  # (frame, id) in a duplicate
    c = {"one_person": 0, "two_people": 0, "duplicates": 0, "two_in_turn": 0}
    for key, rows in runs.items():
        cut = [0] + [k for k in range(1, len(rows)) if rows[k][0] != rows[k - 1][0] + 1]
        for a, b in zip(cut, cut[1:] + [len(rows)]):
            run = rows[a:b]
            if len(run) < frames:
                continue
            two = [person[i] >= 0 and person[j] >= 0 and person[i] != person[j] for _, i, j in run]
            found = [(not hidden[i], not hidden[j]) for _, i, j in run]
            alone = [fi for fi, fj in found if fi != fj]
            in_turn = any(p != q for p, q in pairwise(alone)) and not any(
                fi and fj for fi, fj in found)
            for (f, _, _), t in zip(run, two):
                if not t:
                    one.update({(f, key[0]), (f, key[1])})
            if 2 * sum(two) >= len(run):
                c["two_people"] += 1
                c["two_in_turn"] += in_turn
                continue
            c["one_person"] += 1
            c["duplicates"] += in_turn
            if in_turn:
                dup.update((f, k) for f, _, _ in run for k in key)
    fp = [(int(res.frames[r]), int(res.ids[r])) for r in np.flatnonzero(
        ~np.isin(np.arange(len(res)), m[m >= 0]))]
    switches, last = [], {}
    for r in np.flatnonzero(m >= 0):  # gt rows in (frame, id) order
        g, i = int(gt.ids[r]), int(res.ids[m[r]])
        if last.get(g, i) != i:
            switches.append((int(gt.frames[r]), last[g], i))
        last[g] = i

    def near(where: set, f: int, a: int, b: int) -> bool:
        return bool({(f, a), (f, b), (f - 1, a), (f - 1, b)} & where)

    c.update(false_positives=len(fp), fp_one_person=sum(k in one for k in fp),
             fp_duplicates=sum(k in dup for k in fp), switches=len(switches),
             switches_one_person=sum(near(one, *s) for s in switches),
             switches_duplicates=sum(near(dup, *s) for s in switches))
    return c


def metrics(tally: Tally) -> np.ndarray:
    """COMBINED (IDF1, HOTA, MOTA, IDs) of a tally's sequences."""
    m = combine(tally.scores).row()
    return np.array([m["IDF1"], m["HOTA"], m["MOTA"], m["IDs"]], dtype=float)


def line(label: str, tally: Tally, m: np.ndarray) -> str:
    return (f"{label}: IDF1/HOTA/MOTA {m[0]:.3f}/{m[1]:.3f}/{m[2]:.3f} IDs {m[3]:.0f}; "
            f"re-acquisitions wrong {tally.wrong}/{tally.reacquired}; "
            f"exchanges {tally.exchanges}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", default="crowd d0.4", help="a set of harness.sweeps.generalisation")
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(6)))
    ap.add_argument("--trackers", nargs="+", default=["reta", "pbm"])
    ap.add_argument("--gap", type=int, default=5, help="frames unfound before a re-acquisition")
    ap.add_argument("--length", type=int, help="cut synthetic scenes / replays to N frames")
    ap.add_argument("--events", action="store_true", help="print every wrong re-acquisition")
    ap.add_argument("--untouched", action="store_true", help="allow the set's untouched seeds")
    ap.add_argument("--stacks", action="store_true", help="count stacked targets (docstring)")
    args = ap.parse_args(argv)
    sets = {e.name: e for e in G.SETS}
    if args.set not in sets:
        ap.error(f"--set {args.set!r}: not one of {sorted(sets)}")
    s = sets[args.set]
    held = sorted(set(args.seeds) & set(s.seeds)) if s.role == G.UNTOUCHED else []
    if held and not args.untouched:
        ap.error(f"seeds {held} are {args.set}'s untouched seeds: choose tuning seeds "
                 "(or --untouched to measure, not to choose)")
    trackers = [parse_tracker(t) for t in args.trackers]
    total = {label: Tally() for label, _, _ in trackers}
    per_seed: dict[str, list[np.ndarray]] = {label: [] for label in total}
    for seed in args.seeds:
        tallies = run_seed(set_overrides(args.set, seed, args.length), trackers, args.gap,
                           args.stacks)
        for label, tally in tallies.items():
            m = metrics(tally)
            per_seed[label].append(m)
            print(f"{args.set} seed {seed} {line(label, tally, m)}", flush=True)
            if args.events:
                for e in tally.events:
                    print("    ", e)
            total[label].add(tally)
    for label, tally in total.items():
        m = np.mean(per_seed[label], axis=0)  # the generalisation table's mean over seeds
        m[3] = sum(x[3] for x in per_seed[label])  # IDs summed
        print(f"{args.set} seeds {args.seeds} (mean; IDs summed) {line(label, tally, m)}")
        if args.stacks:
            print(f"{args.set} seeds {args.seeds} {label} stacks: {dict(tally.stacks)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
