"""Trackers tuned on the real choosing sets (issue 35 item 4): the outside trackers and ours
(reta, pbm: the same budget, rows beside their defaults), each tracker's search space of its
``+experiment=tune_<name>`` (``hydra.sweeper.params``), Optuna TPE (sampler seed 0,
``--startup`` random start-up trials, the tracker's defaults enqueued as trial 0 where they
lie in the space), the objective the mean IDF1 over the choosing sets of
``occbench.sweeps.generalisation`` (each set's mean over its seeds, as the table gives it;
``synth-tune`` is not one: synthetic scenes never choose anything), ``--trials`` trials per
tracker (docs/generalisation.md gives the budget and why).

Trials are asked in batches (the start-up trials, then the rest with TPE's constant liar, in
one batch or in the sizes ``--batches`` gives: ``--trials 40 --batches 6 24`` makes its first 16
trials those of a 16-trial study, so both budgets come from one run), and every trial of every
tracker of a batch runs in one harness run per set and seed: all see
the same frames and detections (the front end's cache keeps the silhouette detections), and
the runs write their scores only (``report=false``). A trial that fails on any set (a
recorded failure, a missing score) is told to Optuna as failed, never as a number.

Writes into ``--out``: ``trials.csv`` (every trial's parameters, IDF1 per set and objective,
after each batch), ``provenance.txt`` (date and commit) and each batch's run folders; with
``--write`` (or later ``--write-only``, from ``trials.csv``), the best trial of each tracker as
``conf/tracker/<name>_tuned_real.yaml``, its values exactly the trial's, with where it came
from in its comments (``occbench.sweeps.generalisation`` lists it after ``<name>_tuned``).

    nice -n 10 .venv/bin/python benchmarks/tune_on_choosing.py --trackers norfair motpy \\
        --trials 64 --batches 6 24 24 --within 16 40 --out results/tune_on_choosing --write
    .venv/bin/python benchmarks/tune_on_choosing.py --list     # trackers, spaces and sets
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import textwrap
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from occbench.config.meta import shipped
from occbench.sweeps import generalisation as G
from occbench.sweeps.tune import defaults_of, search_space
from shared_data import use_shared_data

#: the tune experiment (its search space) of each tracker that can be tuned here
EXPERIMENT = {"norfair": "tune_norfair", "motpy": "tune_motpy", "ocsort": "tune_ocsort",
              "bytetrack": "tune_bytetrack", "boxmot_boosttrack": "tune_boosttrack",
              "boxmot_botsort": "tune_botsort", "reta": "tune_reta", "pbm": "tune_pbm"}
SUFFIX = "_tuned_real"
#: each tuned row's colour in the views (``occbench.config.meta``: distinct from every tracker's)
COLOURS = {"norfair": "#ce6dbd", "motpy": "#6b6ecf", "ocsort": "#5254a3",
           "bytetrack": "#e7ba52", "boxmot_boosttrack": "#bd9e39", "boxmot_botsort": "#ad494a",
           "reta": "#fd8d3c", "pbm": "#31a354"}
METRIC = "IDF1"


def space(name: str) -> dict[str, Any]:
    """Optuna distributions of ``name``'s tune experiment (``tracker.<key>`` names)."""
    params = OmegaConf.load(G.CONF / "experiment" / f"{EXPERIMENT[name]}.yaml").hydra.sweeper.params
    return search_space(OmegaConf.to_container(params, resolve=True))


def choosing_sets(names: Sequence[str] | None = None) -> list[G.EvalSet]:
    """The real choosing sets (role tuning, ``synth-tune`` left out), or those of ``names``."""
    sets = [s for s in G.SETS if s.role == G.TUNING and s.name != "synth-tune"]
    if names:
        unknown = sorted(set(names) - {s.name for s in sets})
        if unknown:
            raise SystemExit(f"tune_on_choosing: not a choosing set: {unknown}; "
                             f"choosing sets: {[s.name for s in sets]}")
        sets = [s for s in sets if s.name in names]
    return sets


def tracker_node(name: str, params: Mapping[str, Any]):
    """The tracker config ``name`` with the trial's ``tracker.<key>`` values set."""
    return G.compose([f"tracker={name}", *(f"{k}={v}" for k, v in params.items())]).tracker


def run_batch(batch: Mapping[str, tuple[str, dict]], sets: Sequence[G.EvalSet], out: Path,
              data_root: Path | None) -> pd.DataFrame:
    """IDF1 of every labelled trial (label -> (tracker, params)) on every set, rows
    (label, set, IDF1); NaN where the run recorded a failure of that trial (or of all)."""
    trackers = {label: tracker_node(name, p) for label, (name, p) in batch.items()}
    rows = []
    for s in sets:
        t = G.run_set(s, trackers, out / s.name.replace(" ", "_"), G.trajectories_root(),
                      data_root=data_root, extra=["report=false"])
        for r in t.itertuples():
            value = getattr(r, METRIC) if r.failures == 0 else math.nan
            rows.append({"label": r.tracker, "set": s.name, METRIC: value})
        print(f"  {s.name}: done", flush=True)
    return pd.DataFrame(rows)


def batch_sizes(trials: int, startup: int, batches: Sequence[int] = ()) -> list[int]:
    """Trials asked per batch: the start-up trials, then ``batches`` (the rest in one batch
    when empty); SystemExit when they do not add up to ``trials``."""
    first = min(startup, trials)
    sizes = [first, *(batches or ([trials - first] if trials > first else []))]
    if sum(sizes) != trials or min(sizes) < 1:
        raise SystemExit(f"tune_on_choosing: batches {sizes} do not make {trials} trials")
    return sizes


def tune(names: Sequence[str], sets: Sequence[G.EvalSet], trials: int, startup: int,
         out: Path, data_root: Path | None = None,
         batches: Sequence[int] = ()) -> tuple[dict, pd.DataFrame]:
    """One TPE study per tracker of ``names`` (module docstring); returns the studies by
    name and the trials' table (also ``out/trials.csv``)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    studies, spaces = {}, {}
    for name in names:
        spaces[name] = space(name)
        sampler = optuna.samplers.TPESampler(seed=0, n_startup_trials=startup,
                                             constant_liar=True)
        studies[name] = optuna.create_study(direction="maximize", sampler=sampler)
        studies[name].enqueue_trial(defaults_of(G.compose([f"tracker={name}"]), spaces[name]))
    out.mkdir(parents=True, exist_ok=True)
    (out / "provenance.txt").write_text(G.provenance() + "\n")
    table: list[dict] = []
    for b, n in enumerate(batch_sizes(trials, startup, batches)):
        batch, asked = {}, {}
        for name, study in studies.items():
            for _ in range(n):
                trial = study.ask(spaces[name])
                label = f"{name}__t{trial.number}"
                batch[label], asked[label] = (name, trial.params), (study, trial)
        print(f"batch {b}: {len(batch)} trials on {len(sets)} sets", flush=True)
        wide = run_batch(batch, sets, out / f"batch{b}", data_root).pivot(
            index="label", columns="set", values=METRIC)
        for label, (study, trial) in asked.items():
            per_set = wide.loc[label, [s.name for s in sets]]
            value = float(per_set.mean()) if per_set.notna().all() else math.nan
            if math.isnan(value):
                study.tell(trial, state=optuna.trial.TrialState.FAIL)
            else:
                study.tell(trial, value)
            table.append({"tracker": batch[label][0], "trial": trial.number, **trial.params,
                          **per_set.to_dict(), "objective": value})
        pd.DataFrame(table).to_csv(out / "trials.csv", index=False, lineterminator="\n")
    return studies, pd.DataFrame(table)


def best_within(table: pd.DataFrame, name: str, n: int | None = None) -> pd.Series:
    """The row of ``name``'s best trial (the first of equal ones) among its first ``n``
    (trial numbers below ``n``; None = all)."""
    rows = table[(table["tracker"] == name) & (table["trial"] < (n or math.inf))]
    return rows.loc[rows["objective"].idxmax()]


def _value(dist: Any, v: Any) -> Any:
    """A trial's value as the config takes it (an int parameter read back from the csv as
    a float is an int again)."""
    return int(v) if "Int" in type(dist).__name__ else float(v)


def config_text(name: str, table: pd.DataFrame, sets: Sequence[G.EvalSet], startup: int,
                provenance: str, within: Sequence[int] = ()) -> str:
    """``conf/tracker/<name>_tuned_real.yaml``: ``name``'s best trial of ``table`` (the
    trials' table) over its defaults, with its provenance in comments (sets, trials,
    objective, sampler, commit; the best of the first ``within`` trials too)."""
    dists = space(name)
    rows = table[table["tracker"] == name].set_index("trial")
    best = best_within(table, name)
    smaller = "".join(f"; best of the first {n}: trial {int(r['trial'])}, {r['objective']:.4f}"
                      for n in within for r in [best_within(table, name, n)])
    full = set(defaults_of(G.compose([f"tracker={name}"]), dists)) == set(dists)
    defaults_note = "" if full else ("\n# (trial 0 held the defaults that lie in the space, the "
                                     "others sampled)")
    per_set = ", ".join(f"{s.name} {best[s.name]:.3f}" for s in sets)
    lines = [
        f"# {name} at the best of {len(rows)} trials on the real choosing sets of issue 35",
        "# (benchmarks/tune_on_choosing.py; docs/generalisation.md). Objective: mean IDF1 over",
        f"# {', '.join(s.name for s in sets)}",
        f"# (each set's mean over its seeds). Optuna TPE, sampler seed 0, {startup} random",
        f"# start-up trials, the defaults first; the search space of +experiment="
        f"{EXPERIMENT[name]}{defaults_note}.", f"# Run {provenance}.",
        *textwrap.wrap(f"Best (trial {int(best['trial'])}): mean IDF1 {best['objective']:.4f}; "
                       f"trial 0 {rows.loc[0, 'objective']:.4f}{smaller}.", 90,
                       initial_indent="# ", subsequent_indent="# "),
        *textwrap.wrap(f"Per set: {per_set}.", 90, initial_indent="# ",
                       subsequent_indent="# "),
        "defaults:", f"  - {name}", "  - _self_"]
    parent = shipped(name)  # ours stay ours (versus.md gives their verdicts), drawn as theirs
    node = OmegaConf.create({"meta": {"label": f"{name}{SUFFIX}", "colour": COLOURS[name],
                                      "role": "ours" if parent.role == "ours" else "outside",
                                      "style": parent.style if parent.role == "ours" else "boxes"}})
    for k, dist in dists.items():
        OmegaConf.update(node, k.removeprefix("tracker."), _value(dist, best[k]), force_add=True)
    return "\n".join(lines) + "\n" + OmegaConf.to_yaml(node)


def write_configs(out: Path, sets: Sequence[G.EvalSet], startup: int,
                  within: Sequence[int] = (), folder: Path | None = None) -> list[Path]:
    """``<name>_tuned_real.yaml`` of every tracker of ``out/trials.csv`` into ``folder``
    (default ``conf/tracker``), the run's provenance read from ``out/provenance.txt``."""
    table = pd.read_csv(out / "trials.csv")
    provenance = (out / "provenance.txt").read_text().strip()
    paths = []
    for name in dict.fromkeys(table["tracker"]):
        path = (folder or G.CONF / "tracker") / f"{name}{SUFFIX}.yaml"
        path.write_text(config_text(name, table, sets, startup, provenance, within))
        paths.append(path)
    return paths


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trackers", nargs="+", default=list(EXPERIMENT), choices=list(EXPERIMENT))
    ap.add_argument("--trials", type=int, default=16, help="trials per tracker (default 16)")
    ap.add_argument("--startup", type=int, default=10, help="random start-up trials (10)")
    ap.add_argument("--batches", nargs="+", type=int, default=[],
                    help="trials per batch after the start-up (default: the rest in one)")
    ap.add_argument("--within", nargs="+", type=int, default=[],
                    help="also name the best of the first N trials in the written config")
    ap.add_argument("--sets", nargs="+", help="a subset of the choosing sets (smoke runs)")
    ap.add_argument("--out", type=Path, help="output folder (trials.csv, run folders)")
    ap.add_argument("--write", action="store_true",
                    help=f"write conf/tracker/<name>{SUFFIX}.yaml (the best trial)")
    ap.add_argument("--write-only", action="store_true",
                    help="run nothing: write the configs from --out's trials.csv (a study "
                    "stopped after a batch, or re-written)")
    ap.add_argument("--list", action="store_true", help="trackers, spaces and sets; run nothing")
    args = ap.parse_args(argv)
    sets = choosing_sets(args.sets)
    if args.list:
        for name in args.trackers:
            print(name, {k: str(d) for k, d in space(name).items()})
        print("choosing sets:", [s.name for s in sets])
        return 0
    if args.out is None:
        ap.error("--out is required")
    if (args.write or args.write_only) and args.sets:
        ap.error("--write takes the whole choosing split (no --sets)")
    if not args.write_only:
        data_root = use_shared_data()
        os.chdir(ROOT)  # the configs' data paths are relative to the repository root
        print("choosing sets:", [s.name for s in sets], flush=True)
        batch_sizes(args.trials, args.startup, args.batches)  # refused before any run
        _, table = tune(args.trackers, sets, args.trials, args.startup, args.out, data_root,
                        args.batches)
        for name in args.trackers:
            best = best_within(table, name)
            print(f"{name}: best trial {int(best['trial'])}, mean IDF1 {best['objective']:.4f}")
    if args.write or args.write_only:
        for path in write_configs(args.out, sets, args.startup, args.within):
            print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
