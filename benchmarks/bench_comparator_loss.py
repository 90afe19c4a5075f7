"""PBM's comparators (mean shift, the colour particle filter) under PBM's single-target
protocol with candidate loss and restart rules (``occbench.trackers.comparators.loss``): the figures
the rules were chosen on, and those they are reported on.

Every candidate follows every person of a set under ``+experiment=pbm_table1``'s protocol
(``occbench.pipeline.protocols.run_single_target``: started from the person's ground-truth
box, a restart reported under a new id); frames are read and detected once per set. Prints,
per candidate, each set's IDF1 and the IDF1 / MOTA pooled over the chosen sets (counts
summed, ratios recomputed), then PBM Table 1's and Tables 2-4's columns pooled the same way.

Which data is which (docs/adaptations.md, "PBM's comparators"): ``--sets tuning`` (the
default) is CAVIAR OneLeaveShop1cor frames 1-150 and EnterExitCrossingPaths1cor frames 1-180
with the front end's silhouette detector: the rules are chosen there, on pooled IDF1.
``--sets untouched`` (frames 151-295 and 181-383) and ``--sets table`` (the tables' own data:
PETS09-S2L1 replayed, foreground blobs) only report.

    nice python benchmarks/bench_comparator_loss.py --sets tuning \\
        "ms_off=meanshift" "ms_08_3=meanshift:tracker.loss.threshold=0.8,tracker.loss.frames=3"

A candidate is ``<config>`` or ``<label>=<config>[:<override>,...]`` (Hydra overrides of the
composed config; ``tracker.max_targets=1`` is always added, as ``pbm_single_target`` sets it).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench_reacquisition import parse_tracker  # noqa: E402
from shared_data import use_shared_data  # noqa: E402

from occbench.metrics import combine, score_sequence  # noqa: E402
from occbench.metrics.paper import combine as combine_paper  # noqa: E402
from occbench.metrics.paper import paper_counts  # noqa: E402
from occbench.config.build import build_source, build_tracker, load_sequences  # noqa: E402
from occbench.pipeline.protocols import run_single_target  # noqa: E402
from occbench.sweeps import generalisation as G  # noqa: E402

DATA = use_shared_data()  # $OCCBENCH_SHARED: EnterExitCrossingPaths1cor is not shipped

ECP = ("dataset=mot", "dataset.root={shared}/CAVIAR-EnterExitCrossingPaths1cor")
SETS: dict[str, dict[str, tuple[str, ...]]] = {
    "tuning": {"cav1-150": ("dataset=caviar", "dataset.frames=[1,150]", "detector=silhouette"),
               "ecp1-180": (*ECP, "dataset.frames=[1,180]", "detector=silhouette")},
    "untouched": {"cav151-295": ("dataset=caviar", "dataset.frames=[151,295]",
                                 "detector=silhouette"),
                  "ecp181-383": (*ECP, "dataset.frames=[181,383]", "detector=silhouette")},
    "table": {"PETS09": ()},  # pbm_table1's own dataset and detector
}
PAPER = ("PBM_MT", "PBM_ML", "PBM_Over", "PBM_IDsw/traj", "PBM_IDs/traj", "PBM_IDs/frame",
         "PBM_dx%", "PBM_dy%", "PBM_dw%", "PBM_dh%")


def run_set(overrides: list[str], candidates: list[tuple[str, str, list[str]]]) -> dict:
    """label -> (list of SequenceScore, dict of PaperCounts) over the set's sequences."""
    base = ["+experiment=pbm_table1", *overrides]
    cfg = G.compose(base)
    nodes = {label: G.compose([*base, f"tracker={config}", "tracker.max_targets=1",
                               *extra]).tracker for label, config, extra in candidates}
    out: dict = {label: ([], {}) for label in nodes}
    for seq in load_sequences(cfg.dataset):
        builders = {label: (lambda n=n, label=label: build_tracker(label, n))
                    for label, n in nodes.items()}
        runs = run_single_target(builders, seq, build_source(cfg.detector),
                                 str(cfg.get("foreground", "auto")), cfg.get("background"))
        for label, res in runs.items():
            if res.error:
                raise SystemExit(f"{label} failed on {seq.info.name}: {res.error}")
            out[label][0].append(score_sequence(seq.gt.table, res.table))
            out[label][1][seq.info.name] = paper_counts(seq.gt.table, res.table,
                                                        followers=res.followers)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("candidates", nargs="+", help="<label>=<config>[:<override>,...]")
    ap.add_argument("--sets", choices=sorted(SETS), default="tuning")
    args = ap.parse_args(argv)
    candidates = [parse_tracker(c) for c in args.candidates]
    shared = str(DATA)
    per_set = {name: run_set([o.format(shared=shared) for o in ov], candidates)
               for name, ov in SETS[args.sets].items()}
    print(f"sets: {args.sets} ({', '.join(per_set)}); IDF1 per set, then pooled")
    print("label".ljust(16) + "".join(f"{n:>12}" for n in per_set)
          + f"{'IDF1':>8}{'MOTA':>8}" + "".join(f"{c[4:]:>12}" for c in PAPER))
    for label, _, _ in candidates:
        scores = [s for name in per_set for s in per_set[name][label][0]]
        papers = {f"{name}/{k}": v for name in per_set
                  for k, v in per_set[name][label][1].items()}
        each = [combine(per_set[name][label][0]).clear.ratios()["IDF1"] for name in per_set]
        pooled = combine(scores).clear.ratios()
        paper = combine_paper(papers)["COMBINED"]
        print(label.ljust(16) + "".join(f"{v:12.3f}" for v in each)
              + f"{pooled['IDF1']:8.3f}{pooled['MOTA']:8.3f}"
              + "".join(f"{paper[c]:12.3g}" for c in PAPER))


if __name__ == "__main__":
    main()
