"""Which of our rules paper mode lacks explains a paper-mode figure (issue 37 item 6): runs a
paper table's experiment once with the paper-mode tracker as it is beside one copy of it per
adaptation turned back to our default's value (one at a time, every other one left as in the
paper), all in one harness run (the same detections for all), and plots chosen metrics of
one sequence per copy.

    python benchmarks/paper_mode_ablation.py --experiment reta_table3 --paper reta_paper \\
        --ours reta --sequence PETS09-S2L1 --out docs/img/ablation_reta_paper_pets.png

The adaptations compared are the keys of ``adaptations:`` whose values differ between
conf/tracker/<paper>.yaml (with what it inherits) and conf/tracker/<ours>.yaml. The run is
``occbench +experiment=E tracker=<group>`` with the group's other trackers removed and
``+tracker@tracker.<paper>_with_<key>=<paper> tracker.<paper>_with_<key>.adaptations.<key>=
<ours' value>`` added per key; the figures go to ``<out>.csv`` beside the PNG.
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
from pathlib import Path

from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[1]


def adaptations(tracker: str) -> dict:
    """conf/tracker/<tracker>.yaml's adaptations, with those of the configs it inherits."""
    cfg = OmegaConf.load(ROOT / "conf" / "tracker" / f"{tracker}.yaml")
    merged: dict = {}
    for parent in cfg.get("defaults", []):
        if isinstance(parent, str) and parent != "_self_":
            merged.update(adaptations(parent))
    merged.update(OmegaConf.to_container(cfg.get("adaptations", {})) or {})
    merged.pop("_target_", None)
    return merged


def switches(paper: str, ours: str) -> dict:
    """key -> our default's value, for every adaptation paper mode sets otherwise."""
    p, o = adaptations(paper), adaptations(ours)
    return {k: v for k, v in o.items() if p.get(k, v) != v}


def _value(v) -> str:
    """``v`` as a Hydra override value."""
    if isinstance(v, dict):
        return "{" + ",".join(f"{k}:{_value(x)}" for k, x in v.items()) + "}"
    return "null" if v is None else str(v).lower() if isinstance(v, bool) else str(v)


def overrides(args, keys: dict) -> list[str]:
    """The run's tracker overrides: the group's paper tracker alone, plus one copy per key."""
    group = OmegaConf.load(ROOT / "conf" / "tracker" / f"{args.group}.yaml")
    drop = [str(d).split("@")[-1] for d in group.get("defaults", []) if "@" in str(d)]
    out = [f"tracker={args.group}", *(f"~tracker.{k}" for k in drop if k != args.paper)]
    for key, value in keys.items():
        name = f"{args.paper}_with_{key}"
        out += [f"+tracker@tracker.{name}={args.paper}",
                f"++tracker.{name}.adaptations.{key}={_value(value)}"]
    return out


def run(args, keys: dict, out: Path) -> dict[str, dict[str, float]]:
    """The one run; tracker -> the sequence's metrics (reused when the run is already there)."""
    metrics = out / "metrics.csv"
    if not metrics.is_file():
        argv = [sys.executable, "-m", "occbench", f"+experiment={args.experiment}",
                *overrides(args, keys), *args.set, "progress=false", "report=false",
                f"hydra.run.dir={out}"]
        done = subprocess.run(argv, capture_output=True, text=True, check=False)
        if done.returncode != 0 or not metrics.is_file():
            raise SystemExit(f"occbench: {' '.join(argv)} failed:\n{done.stderr[-2000:]}")
    with metrics.open() as fh:
        return {row["tracker"]: {m: float(row[m]) for m in args.metrics}
                for row in csv.DictReader(fh) if row["sequence"] == args.sequence}


def plot(rows: list[tuple[str, dict]], metrics: list[str], title: str, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(metrics), figsize=(4.2 * len(metrics), 0.32 * len(rows) + 1.6),
                             sharey=True)
    for ax, m in zip(axes if len(metrics) > 1 else [axes], metrics, strict=True):
        values = [r[m] for _, r in rows]
        colours = ["#555555"] + ["#1f77b4"] * (len(rows) - 1)
        ax.barh(range(len(rows)), values, color=colours)
        ax.axvline(values[0], color="#555555", lw=0.8, ls="--")
        ax.set_title(m)
        ax.set_yticks(range(len(rows)), [name for name, _ in rows], fontsize=8)
        ax.invert_yaxis()
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--experiment", required=True)
    p.add_argument("--paper", required=True, help="the paper-mode tracker config")
    p.add_argument("--ours", required=True, help="the default tracker config it is compared with")
    p.add_argument("--group", default="papers",
                   help="the experiment's tracker group holding --paper")
    p.add_argument("--sequence", required=True)
    p.add_argument("--metrics", nargs="+", default=["Song_Frag", "Song_IDS", "MOTA"])
    p.add_argument("--keys", nargs="*", help="only these adaptations (default: every one)")
    p.add_argument("--set", nargs="*", default=[], help="further overrides for every run")
    p.add_argument("--runs", type=Path, default=ROOT / "results" / "ablation")
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    keys = switches(args.paper, args.ours)
    unknown = sorted(set(args.keys or []) - set(keys))
    if unknown:
        p.error(f"--keys: {', '.join(unknown)} are not adaptations {args.paper} sets otherwise")
    keys = {k: v for k, v in keys.items() if args.keys is None or k in args.keys}
    found = run(args, keys, args.runs / f"{args.experiment}_{args.paper}")
    rows = [("paper mode", found[args.paper])]
    for key, value in keys.items():
        shown = "" if isinstance(value, dict) else f"={_value(value)}"
        rows.append((f"+ {key}{shown}", found[f"{args.paper}_with_{key}"]))
    with args.out.with_suffix(".csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["run", *args.metrics])
        w.writerows([name, *(r[m] for m in args.metrics)] for name, r in rows)
    plot(rows, args.metrics, f"{args.paper} on {args.sequence} ({args.experiment}): one rule of "
         f"{args.ours} turned on at a time", args.out)
    print(f"wrote {args.out} and {args.out.with_suffix('.csv')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
