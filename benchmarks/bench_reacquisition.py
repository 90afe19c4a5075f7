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

Every run also puts IDF1's misses down to causes (``idf1_losses``; with ``--events``, per
sequence with the persons losing most), and counts issue 28's three failure modes
(``mode_counts``, on the CLEAR matching): (a) *reused*: an id unmatched for more than
``--gap`` frames comes back on another person (``reused_new``: one first matched in the last
``--gap`` frames, a newcomer; ``outlived``: after any gap, an id whose last person is no
longer annotated comes back on another); (b) *phantom*: hidden-person reports (OCCLUDED)
matched to nobody (``phantom_empty``: overlapping no person, IoU < 0.1), of ``hidden`` in all;
(c) *handed*: CLEAR ID switches, each put down to the detections around it: ``merged`` (a
detection covers the person and another, at the switch or the frame before), ``split`` (two
detections lie mostly inside the person's box), ``misses`` (the person had no detection at
IoU >= 0.5 for >= 3 frames before), else ``other``.

For choosing rules on tuning data only (docs/generalisation.md): the sets are those of
``occbench.sweeps.generalisation``; the seeds are the set's own for a tuning set (default),
else yours (``--seeds``); seeds of a set's untouched list are refused unless ``--untouched``
is given (to measure, once, not to choose: then the set's own seeds are the default). Several ``--set`` are run one after the other.

With ``--out DIR``, the IDF1 points lost by cause of every (set, tracker) are also written
there: ``idf1_causes.csv`` (full precision), ``idf1_causes.md`` (docs/generalisation.md's
"Diagnosis by cause" table) and ``idf1_causes.png`` beside them (a stacked bar per row, one
colour per cause of ``idf1_losses.CAUSES``; ``--title`` names it).

    .venv/bin/python benchmarks/bench_reacquisition.py --set "crowd d0.8" --seeds 0 1 \\
        --trackers reta pbm "pbm_rm0=pbm:tracker.adaptations.relative_match=0"

A tracker is ``<config>`` or ``<label>=<config>[:<override>,<override>...]`` (Hydra
overrides of the composed config). Run it niced on a shared machine: ``nice -n 10``.
"""

from __future__ import annotations

import argparse
import pickle
import sys
from collections import Counter
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from idf1_losses import CAUSES, LABELS, idf1_causes, idf1_losses, inside, losses_line  # noqa: E402
from shared_data import use_shared_data  # noqa: E402

from occbench.io.mot import MotTable  # noqa: E402
from occbench.metrics import combine, score_sequence  # noqa: E402
from occbench.metrics.paper import considered, match_rows  # noqa: E402
from occbench.config.build import build_source, build_tracker, load_sequences  # noqa: E402
from occbench.pipeline.loop import frames  # noqa: E402
from occbench.report.figures import save_figure  # noqa: E402
from occbench.sweeps.tables import markdown_table  # noqa: E402
from occbench.sweeps import generalisation as G  # noqa: E402
from occbench.trackers.geometry import iou_matrix  # noqa: E402

DATA = use_shared_data()  # $OCCBENCH_SHARED: the sets not shipped


@dataclass
class Tally:
    """Counts of one tracker over the sequences of a run."""

    reacquired: int = 0
    wrong: int = 0
    exchanges: int = 0
    stacks: Counter = field(default_factory=Counter)  # ``stack_counts`` summed
    modes: Counter = field(default_factory=Counter)  # ``mode_counts`` summed
    missed: Counter = field(default_factory=Counter)  # ``idf1_losses``: IDFN causes summed
    false: Counter = field(default_factory=Counter)  # ... and IDFP causes
    causes: Counter = field(default_factory=Counter)  # ``idf1_causes``: boxes by event
    denominator: int = 0  # ... and IDF1's 2 IDTP + IDFP + IDFN, summed
    events: list[dict] = field(default_factory=list)
    scores: list = field(default_factory=list)

    def add(self, other: Tally) -> None:
        self.reacquired += other.reacquired
        self.wrong += other.wrong
        self.exchanges += other.exchanges
        self.stacks.update(other.stacks)
        self.modes.update(other.modes)
        self.missed.update(other.missed)
        self.false.update(other.false)
        self.causes.update(other.causes)
        self.denominator += other.denominator
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
    out = G._resolve(s.overrides, G.trajectories_root(), DATA) + [f"seed={seed}", "progress=false"]
    if length:
        key = {"dataset=synthetic": "length", "dataset=replay": "max_frames"}
        out += [f"dataset.{key[o]}={length}" for o in out if o in key]
    return out


def run_seed(overrides: list[str], trackers: list[tuple[str, str, list[str]]], gap: int,
             stacks: bool = False, show_losses: bool = False,
             dump: Path | None = None) -> dict[str, Tally]:
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
        unconfirmed = {label: {} for label in built}  # frame -> (K, 4) TENTATIVE boxes
        dets: dict[int, np.ndarray] = {}  # frame -> (N, 4) xywh detections
        gt = seq.gt.table
        for step in frames(seq, build_source(cfg.detector), str(cfg.get("foreground", "auto"))):
            k = step.index
            dets[k] = np.asarray(step.detections.boxes, dtype=np.float64).reshape(-1, 4)
            r = seq.gt.rows_of(k)
            r = r[gt.conf[r] > 0]
            gtb, gti = gt.boxes[r], gt.ids[r]
            for label, tracker in built.items():
                image = None if step.image is None else step.image.copy()
                out = tracker.update(image, step.detections, step.foreground)
                tracks = [t for t in out if t.state.reported]
                unconfirmed[label][k] = np.array([t.box for t in out if not t.state.reported],
                                                 dtype=np.float64).reshape(-1, 4)
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
            tallies[label].modes.update(mode_counts(gt, table, np.asarray(hidden, dtype=bool)
                                                    [order], dets, gap))
            fn, fp = idf1_losses(gt, table, np.asarray(hidden, dtype=bool)[order],
                                 unconfirmed[label])
            tallies[label].missed.update({k: v for k, v in fn.items() if isinstance(k, str)})
            tallies[label].false.update(fp)
            hid = np.asarray(hidden, dtype=bool)[order]
            causes, denominator = idf1_causes(gt, table, match_rows(considered(gt), table), hid,
                                              unconfirmed[label], dets)
            tallies[label].causes.update(causes)
            tallies[label].denominator += denominator
            if dump is not None:  # what idf1_causes read, to study a rule's events offline
                dump.mkdir(parents=True, exist_ok=True)
                with open(dump / f"{seq.info.name}_{label}.pkl", "wb") as fh:
                    pickle.dump(dict(gt=gt, res=table, hidden=hid,
                                     tentative=unconfirmed[label], dets=dets), fh)
            if show_losses:
                print(f"    {seq.info.name} {label}: {losses_line(fn, fp)}")
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


def _cause(f: int, g: int, gt: MotTable, rows_of: dict, dets: dict, run: int = 3) -> str:
    """What the detections did to person g around a switch at frame f (module docstring)."""
    for k in (f - 1, f):
        d, r = dets.get(k, np.zeros((0, 4))), rows_of.get(k, np.zeros(0, dtype=np.int64))
        mine = r[gt.ids[r] == g]
        if not len(d) or not len(mine):
            continue
        covers = inside(gt.boxes[r], d) >= 0.5  # (people, detections): person inside det
        on_g = covers[gt.ids[r] == g][0]
        if (covers[:, on_g].sum(axis=0) >= 2).any():
            return "merged"
        if (inside(d, gt.boxes[mine])[:, 0] >= 0.6).sum() >= 2:
            return "split"
    missed = 0
    for k in range(f - 1, f - 1 - run, -1):
        r = rows_of.get(k, np.zeros(0, dtype=np.int64))
        mine, d = r[gt.ids[r] == g], dets.get(k, np.zeros((0, 4)))
        if not len(mine) or (len(d) and iou_matrix(gt.boxes[mine], d).max() >= 0.5):
            break
        missed += 1
    return "misses" if missed >= run else "other"


def mode_counts(gt: MotTable, res: MotTable, hidden: np.ndarray, dets: dict[int, np.ndarray],
                gap: int) -> Counter:
    """Issue 28's failure modes of a result table (module docstring). ``hidden`` (len(res),)
    bool: OCCLUDED rows; ``dets``: frame -> (N, 4) xywh detections the tracker was given."""
    gt = considered(gt)
    m = match_rows(gt, res)
    c: Counter = Counter(hidden=int(hidden.sum()))
    matched = np.zeros(len(res), dtype=bool)
    matched[m[m >= 0]] = True
    rows_of = gt.frame_index()
    for r in np.flatnonzero(hidden & ~matched):  # (b) hidden reports on nobody
        c["phantom"] += 1
        g = rows_of.get(int(res.frames[r]), np.zeros(0, dtype=np.int64))
        c["phantom_empty"] += not len(g) or iou_matrix(res.boxes[r][None], gt.boxes[g]).max() < 0.1
    last_id: dict[int, tuple[int, int]] = {}  # result id -> (person, frame) last matched
    first: dict[int, int] = {}  # person -> first frame matched
    last_of: dict[int, int] = {}  # person -> id matched last
    for r in np.flatnonzero(m >= 0):  # gt rows in (frame, id) order
        f, g, i = int(gt.frames[r]), int(gt.ids[r]), int(res.ids[m[r]])
        first.setdefault(g, f)
        if i in last_id and last_id[i][0] != g and f - last_id[i][1] - 1 > gap:
            c["reused"] += 1  # (a)
            c["reused_new"] += f - first[g] <= gap
        if i in last_id and last_id[i][0] != g and not (gt.ids[rows_of[f]] == last_id[i][0]).any():
            c["outlived"] += 1  # (a) after any gap: its person is no longer in the picture
        if last_of.get(g, i) != i:  # (c) a CLEAR ID switch
            c["handed"] += 1
            c[_cause(f, g, gt, rows_of, dets)] += 1
        last_id[i], last_of[g] = (g, f), i
    return c


MODES = ("reused", "reused_new", "outlived", "phantom", "phantom_empty", "hidden", "handed", "merged",
         "split", "misses", "other")


def metrics(tally: Tally) -> np.ndarray:
    """COMBINED (IDF1, HOTA, MOTA, IDs) of a tally's sequences."""
    m = combine(tally.scores).row()
    return np.array([m["IDF1"], m["HOTA"], m["MOTA"], m["IDs"]], dtype=float)


def line(label: str, tally: Tally, m: np.ndarray) -> str:
    return (f"{label}: IDF1/HOTA/MOTA {m[0]:.3f}/{m[1]:.3f}/{m[2]:.3f} IDs {m[3]:.0f}; "
            f"re-acquisitions wrong {tally.wrong}/{tally.reacquired}; "
            f"exchanges {tally.exchanges}; modes "
            + " ".join(f"{k} {tally.modes.get(k, 0)}" for k in MODES)
            + "; " + losses_line(tally.missed, tally.false)
            + "; IDF1 lost by cause (points) " + " ".join(
                f"{c} {v:.3f}" for c, v in points(tally).items() if tally.causes.get(c, 0)))


def points(tally: Tally) -> dict[str, float]:
    """Each cause of ``CAUSES`` in IDF1 points: its boxes over IDF1's denominator (2 IDTP +
    IDFP + IDFN), both pooled over the tally's sequences."""
    return {c: tally.causes.get(c, 0) / max(tally.denominator, 1) for c in CAUSES}


def cause_row(name: str, label: str, tally: Tally, m: np.ndarray) -> dict:
    """One (set, tracker) row of the causes table: ``m`` (``metrics``, seed means) and each
    cause of ``CAUSES`` in IDF1 points (its boxes over IDF1's denominator, pooled over seeds)."""
    return {"set": name, "tracker": label, "IDF1": m[0], "HOTA": m[1], "MOTA": m[2],
            **points(tally)}


#: one colour per cause: a wrong id's events warm, false boxes blue, boxes nobody reported grey
COLOURS = {"split": "#d62728", "merged": "#ff7f0e", "dropped_misses": "#bcbd22",
           "contact": "#ffbb78", "reacquired_wrong": "#9467bd", "new_id_other": "#c5b0d5",
           "handover_other": "#f7b6d2", "phantom": "#1f77b4", "double_box": "#aec7e8",
           "found_nobody": "#17becf", "tentative": "#c7c7c7", "unreported": "#7f7f7f"}


def causes_figure(rows: list[dict], title: str = "IDF1 lost by cause"):
    """A stacked horizontal bar per row of ``cause_row``: the IDF1 points each cause of
    ``CAUSES`` takes (the bar's length is about 1 - IDF1, written at its end); every cause is
    in the legend, those absent from every row too."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 0.32 * len(rows) + 1.9))
    left = np.zeros(len(rows))
    for c in CAUSES:
        v = np.array([r[c] for r in rows], dtype=float)
        ax.barh(range(len(rows)), v, left=left, color=COLOURS[c], label=LABELS[c],
                edgecolor="white", linewidth=0.3)
        left += v
    for k, r in enumerate(rows):
        ax.text(left[k] + 0.003, k, f"IDF1 {r['IDF1']:.3f}", va="center", fontsize=7)
    ax.set_yticks(range(len(rows)), [f"{r['set']} · {r['tracker']}" for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, max(left.max(initial=0), 0.01) * 1.18)
    ax.set_xlabel("IDF1 points lost (boxes / (2 IDTP + IDFP + IDFN), pooled over seeds)",
                  fontsize=8)
    ax.legend(fontsize=7, ncol=6, loc="lower center", bbox_to_anchor=(0.5, 1.0))
    ax.set_title(title, fontsize=9, pad=40)
    return fig


def write_causes(rows: list[dict], out: Path, title: str = "IDF1 lost by cause") -> list[Path]:
    """``idf1_causes.csv``, ``.md`` and ``.png`` of ``rows`` (``cause_row``) in ``out``."""
    import pandas as pd

    out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows, columns=["set", "tracker", "IDF1", "HOTA", "MOTA", *CAUSES])
    table.to_csv(out / "idf1_causes.csv", index=False)
    cells = pd.DataFrame([[r["set"], r["tracker"],
                           f"{r['IDF1']:.3f} / {r['HOTA']:.3f} / {r['MOTA']:.3f}",
                           *("0" if r[c] == 0 else f"{r[c]:.3f}" for c in CAUSES)] for r in rows],
                         columns=["set", "tracker", "IDF1 / HOTA / MOTA",
                                  *(LABELS[c] for c in CAUSES)])
    (out / "idf1_causes.md").write_text(markdown_table(cells))  # cells as written
    figure = save_figure(causes_figure(rows, title), out / "idf1_causes.png")
    return [out / "idf1_causes.csv", out / "idf1_causes.md", figure]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", nargs="+", default=["crowd d0.4"],
                    help="sets of occbench.sweeps.generalisation")
    ap.add_argument("--seeds", type=int, nargs="+",
                    help="default: a tuning set's own seeds, else 0-5")
    ap.add_argument("--trackers", nargs="+", default=["reta", "pbm"])
    ap.add_argument("--gap", type=int, default=5, help="frames unfound before a re-acquisition")
    ap.add_argument("--length", type=int, help="cut synthetic scenes / replays to N frames")
    ap.add_argument("--events", action="store_true", help="print every wrong re-acquisition")
    ap.add_argument("--untouched", action="store_true", help="allow the set's untouched seeds")
    ap.add_argument("--stacks", action="store_true", help="count stacked targets (docstring)")
    ap.add_argument("--dump", type=Path, help="pickle each run's gt, tracks and detections here")
    ap.add_argument("--out", type=Path, help="write the IDF1 causes' table and figure here")
    ap.add_argument("--title", default="IDF1 lost by cause", help="the figure's title")
    args = ap.parse_args(argv)
    sets = {e.name: e for e in G.SETS}
    bad = [n for n in args.set if n not in sets]
    if bad:
        ap.error(f"--set {bad}: not in {sorted(sets)}")
    trackers = [parse_tracker(t) for t in args.trackers]
    rows = []
    for name in args.set:
        s = sets[name]
        own = s.role == G.TUNING or args.untouched  # measuring an untouched set: its seeds
        seeds = args.seeds or (list(s.seeds) if own else list(range(6)))
        held = sorted(set(seeds) & set(s.seeds)) if s.role == G.UNTOUCHED else []
        if held and not args.untouched:
            ap.error(f"seeds {held} are {name}'s untouched seeds: choose tuning seeds "
                     "(or --untouched to measure, not to choose)")
        rows += run_set(name, seeds, trackers, args)
    if args.out:
        for path in write_causes(rows, args.out, args.title):
            print(f"wrote {path}")
    return 0


def run_set(name: str, seeds: list[int], trackers: list, args) -> list[dict]:
    """Print every tracker's line per seed and over the seeds of set ``name``; the causes
    table's rows (``cause_row``), one per tracker."""
    total = {label: Tally() for label, _, _ in trackers}
    per_seed: dict[str, list[np.ndarray]] = {label: [] for label in total}
    for seed in seeds:
        dump = args.dump / name.replace(" ", "_") / f"seed{seed}" if args.dump else None
        tallies = run_seed(set_overrides(name, seed, args.length), trackers, args.gap,
                           args.stacks, args.events, dump)
        for label, tally in tallies.items():
            m = metrics(tally)
            per_seed[label].append(m)
            print(f"{name} seed {seed} {line(label, tally, m)}", flush=True)
            if args.events:
                for e in tally.events:
                    print("    ", e)
            total[label].add(tally)
    rows = []
    for label, tally in total.items():
        m = np.mean(per_seed[label], axis=0)  # the generalisation table's mean over seeds
        m[3] = sum(x[3] for x in per_seed[label])  # IDs summed
        print(f"{name} seeds {seeds} (mean; IDs summed) {line(label, tally, m)}", flush=True)
        if args.stacks:
            print(f"{name} seeds {seeds} {label} stacks: {dict(tally.stacks)}")
        rows.append(cause_row(name, label, tally, m))
    return rows


if __name__ == "__main__":
    raise SystemExit(main())
