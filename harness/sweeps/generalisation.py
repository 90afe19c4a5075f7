"""Generalisation table: every tracker x every evaluation set, marking the sets any default
or tuned parameter was chosen on (``tuning``) and those nobody chose anything on
(``untouched``).

An evaluation set is a list of Hydra overrides (dataset, detector, their keys) run at one
or more seeds; every tracker of a set runs in one ``occbench.pipeline.experiment.run_experiment``, so all of
them see the same frames and the same detections. A set run at several seeds reports the
mean of its COMBINED IDF1 / HOTA / MOTA over the seeds.

Which data is which: each set's ``role`` and ``description`` below; docs/generalisation.md
gives the split (issue 28's, and issue 35's with PETS09-S2L1-real frames 1-400 for choosing)
and why each seed range counts as untouched or looked at.

The EnterExitCrossingPaths1cor, PETS09-S2L1-real and lobby sets read the folder given as
``data_root`` (not shipped with the project: the caller says where it is; without it they are
skipped with a message).

Used by ``benchmarks/bench_generalisation.py`` (the command line); ``run_table`` is the
library entry point.
"""

from __future__ import annotations

import datetime as _dt
import logging
import math
import subprocess
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
from hydra import compose as _compose
from hydra import initialize_config_dir
from omegaconf import OmegaConf, open_dict

from occbench.config import register
from occbench.config.build import build_tracker
from occbench.errors import RunError
from occbench.metrics import COMBINED
from occbench.pipeline.experiment import run_experiment
from occbench.report.tables import number

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
CONF = ROOT / "conf"
METRICS = ("IDF1", "HOTA", "MOTA")
TUNING, UNTOUCHED = "tuning", "untouched"
#: synthetic seeds never used for any choice (the project used 0-15 and 100)
UNTOUCHED_SEEDS = (1000, 1001)
#: crowd seeds never used for any choice (one exchange moves a seed by up to 0.1 IDF1)
CROWD_SEEDS = tuple(range(2000, 2010))
#: every tracker of ours and outside, in table order; unavailable ones are skipped, and
#: every conf/tracker/<name><suffix>.yaml of ``TUNED`` is added after the tracker it tunes
TRACKERS = ("baseline", "reta", "reta_paper", "pbm", "pbm_paper", "bytetrack", "ocsort",
            "norfair", "motpy", "boxmot_botsort", "boxmot_bytetrack", "boxmot_ocsort",
            "boxmot_deepocsort", "boxmot_hybridsort", "boxmot_boosttrack",
            "boxmot_occluboost", "boxmot_sfsort")
#: tuned rows, in table order: ``_tuned`` on synthetic data (``+experiment=tune_<name>``),
#: ``_tuned_real`` on the real choosing sets (``benchmarks/tune_on_choosing.py``)
TUNED = ("_tuned", "_tuned_real")


@dataclass(frozen=True)
class EvalSet:
    """One evaluation set.

    Attributes:
        name: short name (a table column).
        role: ``tuning`` (something was chosen on it) or ``untouched``.
        overrides: Hydra overrides selecting dataset, detector and their keys.
        seeds: values of the top-level ``seed`` (rendering and detector noise), one run each.
        quick: part of the quick subset (``--quick``).
        description: one line for the legend of the table.
        requires: folders under the trajectories folder (``trajectories_root()``), or under
            the caller's ``data_root`` when they start with ``data:``, that must exist; a set
            whose data is absent is skipped with a message.
    """

    name: str
    role: str
    overrides: tuple[str, ...]
    seeds: tuple[int, ...] = (0,)
    quick: bool = False
    description: str = ""
    requires: tuple[str, ...] = field(default=())


CAVIAR = ("dataset=caviar",)
GT03 = ("detector=noisy_gt", "detector.miss_rate=0.3")
SILHOUETTE = ("detector=silhouette",)


def _replay(name: str, *extra: str) -> tuple[str, ...]:
    return ("dataset=replay", f"dataset.gt_path=${{trajectories:{name}}}", *extra)


ECP = "CAVIAR-EnterExitCrossingPaths1cor"
#: the second corridor sequence (not shipped): frames and gt in MOT layout under data_root
ECP_SET = ("dataset=mot", f"dataset.root=${{data:{ECP}}}")
PETS_REAL = "PETS09-S2L1-real"
#: PETS 2009 S2L1 View_001 frames 1-400, real pixels at 480x360 (not shipped); its frames
#: 401-795 are kept out of the data folder as untouched footage
PETS_REAL_SET = ("dataset=mot", f"dataset.root=${{data:{PETS_REAL}}}",
                 "dataset.frames=[1,400]")
LOBBY = "CAVIAR-lobby"
#: the lobby's multi-person reporting clips (docs/generalisation.md, "Lobby": nothing is chosen
#: or fitted on them)
LOBBY_REPORTED = ("CAVIAR1-Browse1-f0630-0745", "CAVIAR1-Fight_RunAway1-f0319-0379",
                  "CAVIAR1-Fight_RunAway2-f0300-0385", "CAVIAR1-Walk2-f0800-0999",
                  "CAVIAR1-Walk3-f0212-0772")
#: the lobby's choosing clips C (docs/generalisation.md, "Lobby"); with noisy ground truth a
#: choosing set for pbm's and reta's identity rules
LOBBY_CHOSEN = ("CAVIAR1-Browse2-f0548-0749", "CAVIAR1-Browse4-f0278-0364",
                "CAVIAR1-Rest_FallOnFloor-f0655-0935", "CAVIAR1-Rest_InChair-f0475-0771",
                "CAVIAR1-Walk3-f1096-1378", "CAVIAR1-Walk2-f0400-0599")


SETS: tuple[EvalSet, ...] = (
    EvalSet("synth-tune", TUNING, ("dataset=synthetic", "dataset.length=120"), (100,),
            description="the tune_* data: synthetic suite, seed 100, 120 frames, exact detections"),
    EvalSet("synth", UNTOUCHED, ("dataset=synthetic", *GT03), UNTOUCHED_SEEDS, quick=True,
            description="synthetic suite (8 scenes x 150 frames), noisy gt miss 0.3"),
    EvalSet("cav1-150 gt", TUNING, (*CAVIAR, "dataset.frames=[1,150]", *GT03), UNTOUCHED_SEEDS,
            quick=True, description="CAVIAR OneLeaveShop1cor frames 1-150, noisy gt miss 0.3"),
    EvalSet("cav151-295 gt", UNTOUCHED, (*CAVIAR, "dataset.frames=[151,295]", *GT03),
            UNTOUCHED_SEEDS, quick=True,
            description="CAVIAR OneLeaveShop1cor frames 151-295, noisy gt miss 0.3"),
    EvalSet("cav1-150 sil", TUNING, (*CAVIAR, "dataset.frames=[1,150]", *SILHOUETTE), (0,),
            quick=True,
            description="CAVIAR OneLeaveShop1cor frames 1-150, the front end's silhouette detector"),
    EvalSet("cav151-295 sil", UNTOUCHED, (*CAVIAR, "dataset.frames=[151,295]", *SILHOUETTE),
            (0,), quick=True,
            description="CAVIAR OneLeaveShop1cor frames 151-295, the silhouette detector"),
    EvalSet("ecp1-180 sil", TUNING, (*ECP_SET, "dataset.frames=[1,180]", *SILHOUETTE), (0,),
            quick=True, requires=(f"data:{ECP}",),
            description="CAVIAR EnterExitCrossingPaths1cor frames 1-180 (first crossing), "
            "the silhouette detector"),
    EvalSet("ecp181-383 sil", UNTOUCHED, (*ECP_SET, "dataset.frames=[181,383]", *SILHOUETTE),
            (0,), quick=True, requires=(f"data:{ECP}",),
            description="CAVIAR EnterExitCrossingPaths1cor frames 181-383 (second crossing), "
            "the silhouette detector"),
    EvalSet("ecp1-180 gt", TUNING, (*ECP_SET, "dataset.frames=[1,180]", *GT03),
            UNTOUCHED_SEEDS, requires=(f"data:{ECP}",),
            description="CAVIAR EnterExitCrossingPaths1cor frames 1-180, noisy gt miss 0.3"),
    EvalSet("ecp181-383 gt", UNTOUCHED, (*ECP_SET, "dataset.frames=[181,383]", *GT03),
            UNTOUCHED_SEEDS, requires=(f"data:{ECP}",),
            description="CAVIAR EnterExitCrossingPaths1cor frames 181-383, noisy gt miss 0.3"),
    EvalSet("pets1-400 sil", TUNING, (*PETS_REAL_SET, *SILHOUETTE), (0,), quick=True,
            requires=(f"data:{PETS_REAL}",),
            description="PETS09-S2L1 View_001 real pixels (480x360, 7 fps) frames 1-400, "
            "the silhouette detector (issue 35: groups walking and crossing)"),
    EvalSet("pets1-400 gt", TUNING, (*PETS_REAL_SET, *GT03), UNTOUCHED_SEEDS,
            requires=(f"data:{PETS_REAL}",),
            description="PETS09-S2L1 View_001 real pixels frames 1-400, noisy gt miss 0.3"),
    EvalSet("lobby gt", UNTOUCHED, ("dataset=mot", f"dataset.root=${{data:{LOBBY}}}",
                                    f"dataset.sequences=[{','.join(LOBBY_REPORTED)}]", *GT03),
            (1000,), requires=(f"data:{LOBBY}",),
            description="the five multi-person CAVIAR lobby clips nobody chooses on (a second "
            "camera, looking down), noisy gt miss 0.3"),
    EvalSet("lobby-C gt", TUNING, ("dataset=mot", f"dataset.root=${{data:{LOBBY}}}",
                                   f"dataset.sequences=[{','.join(LOBBY_CHOSEN)}]", *GT03),
            UNTOUCHED_SEEDS, requires=(f"data:{LOBBY}",),
            description="the six CAVIAR lobby clips of the lobby's choosing set C, noisy gt "
            "miss 0.3 (for choosing pbm's and reta's identity rules)"),
    EvalSet("OLS2cor", UNTOUCHED, _replay("CAVIAR-OneLeaveShop2cor", *GT03), (1000,),
            description="CAVIAR OneLeaveShop2cor trajectories replayed (25 fps), noisy gt miss 0.3",
            requires=("CAVIAR-OneLeaveShop2cor",)),
    EvalSet("PETS09", UNTOUCHED, _replay("PETS09-S2L1", *GT03), (1000,),
            description="PETS09-S2L1 trajectories replayed (7 fps), noisy gt miss 0.3",
            requires=("PETS09-S2L1",)),
    EvalSet("PETS09 401-795", UNTOUCHED,
            _replay("PETS09-S2L1", "dataset.frames=[401,795]", *GT03), (1000,),
            description="PETS09-S2L1 trajectories replayed, frames 401-795 only (no frame of "
            "the choosing set pets1-400), noisy gt miss 0.3", requires=("PETS09-S2L1",)),
    EvalSet("TUD-Campus", UNTOUCHED,
            _replay("TUD-Campus", "dataset.width=640", "dataset.height=480", "dataset.fps=25",
                    *GT03), (1000,), quick=True,
            description="TUD-Campus trajectories replayed (640x480, 25 fps), noisy gt miss 0.3",
            requires=("TUD-Campus",)),
    *(EvalSet(f"crowd d{d}", UNTOUCHED,
              ("dataset=synthetic", "dataset.scenarios=[crowd]", "dataset.people=12",
               f"dataset.density={d}", *GT03), CROWD_SEEDS,
              description=f"synthetic crowd, 12 people at {d} persons/m^2, noisy gt miss 0.3")
      for d in (0.2, 0.4, 0.8)),
)


# --------------------------------------------------------------------------- configs


def compose(overrides: Sequence[str]):
    """The project's config composed with ``overrides`` (no Hydra app needed)."""
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return _compose("config", overrides=list(overrides))


def trajectories_root() -> Path:
    """The folder of replayable trajectories: the parent of ``dataset=replay``'s default
    ``gt_path`` (relative paths from the working directory, as the app reads them)."""
    return Path(str(compose(["dataset=replay"]).dataset.gt_path)).parent


#: where ``data:`` folders are looked for when no ``data_root`` is given (never exists)
NO_DATA_ROOT = Path("data_root_not_given")


def _resolve(overrides: Iterable[str], trajectories: Path,
             data_root: Path | None = None) -> list[str]:
    out = []
    for o in overrides:
        for tag, folder in (("${trajectories:", trajectories),
                            ("${data:", data_root or NO_DATA_ROOT)):
            if tag in o:
                key, rest = o.split(tag, 1)
                name, tail = rest.split("}", 1)
                o = f"{key}{folder / name}{tail}"
        out.append(o)
    return out


def missing_data(s: EvalSet, trajectories: Path, data_root: Path | None = None) -> list[Path]:
    """The folders ``s.requires`` names that do not exist."""
    paths = [(data_root or NO_DATA_ROOT) / r.removeprefix("data:") if r.startswith("data:")
             else trajectories / r for r in s.requires]
    return [p for p in paths if not p.exists()]


def ordered_trackers() -> list[str]:
    """``TRACKERS``, each followed by its tuned rows (``conf/tracker/<name><TUNED>.yaml``)."""
    tuned = sorted({p.stem for x in TUNED for p in (CONF / "tracker").glob(f"*{x}.yaml")})
    names = []
    for n in TRACKERS:
        names.append(n)
        names += [f"{n}{suffix}" for suffix in TUNED if f"{n}{suffix}" in tuned]
    return names + [t for t in tuned if t not in names]


def available_trackers(names: Iterable[str] | None = None) -> tuple[dict, dict[str, str]]:
    """Tracker configs by name whose code imports, and the skipped ones with the reason.

    ``names`` None = ``TRACKERS`` plus every ``conf/tracker/*_tuned.yaml`` (after the
    tracker it tunes).
    """
    if names is None:
        names = ordered_trackers()
    configs, skipped = {}, {}
    for n in names:
        if not (CONF / "tracker" / f"{n}.yaml").is_file():
            skipped[n] = "no conf/tracker/%s.yaml" % n
            continue
        node = compose([f"tracker={n}"]).tracker
        try:
            build_tracker(n, node)
        except (RunError, ImportError) as err:
            skipped[n] = str(err).split("\n")[0][:200]
            continue
        configs[n] = node
    return configs, skipped


# --------------------------------------------------------------------------- running


def run_set(s: EvalSet, trackers: dict, out_dir: Path, trajectories: Path,
            length: int | None = None, data_root: Path | None = None,
            extra: Sequence[str] = ()) -> pd.DataFrame:
    """Run every tracker on set ``s`` at each of its seeds; one row per tracker with the
    mean COMBINED metrics over the seeds (``n_seeds``, ``failures`` too). ``extra``: further
    overrides of every run (e.g. ``report=false``: the scores only)."""
    rows = []
    for seed in s.seeds:
        overrides = _resolve(s.overrides, trajectories, data_root) + [
            f"seed={seed}", "progress=false", *extra]
        if length is not None:  # exploring: shorter synthetic scenes and replays
            key = {"dataset=synthetic": "length", "dataset=replay": "max_frames"}
            overrides += [f"dataset.{key[o]}={length}" for o in overrides if o in key]
        cfg = compose(overrides)
        with open_dict(cfg):
            cfg.tracker = OmegaConf.create({n: OmegaConf.to_container(c) for n, c in trackers.items()})
        res = run_experiment(cfg, out_dir / f"seed{seed}")
        comb = res.metrics[res.metrics["sequence"] == COMBINED]
        for n in trackers:
            r = comb[comb["tracker"] == n]
            failed = [f.message for f in res.failures if f.tracker in (n, "*")]
            row = {"tracker": n, "seed": seed, "failures": len(failed)}
            for m in METRICS:
                row[m] = float(r[m].iloc[0]) if len(r) else math.nan
            rows.append(row)
    per_seed = pd.DataFrame(rows)
    out = per_seed.groupby("tracker", sort=False).agg(
        **{m: (m, "mean") for m in METRICS}, n_seeds=("seed", "count"),
        failures=("failures", "sum")).reset_index()
    out.insert(0, "role", s.role)
    out.insert(0, "set", s.name)
    return out


def run_table(sets: Sequence[EvalSet], trackers: dict, out_dir: Path,
              length: int | None = None, data_root: Path | None = None,
              extra: Sequence[str] = ()) -> pd.DataFrame:
    """Every tracker on every set (skipping sets whose data is absent, with a message;
    ``data_root``: the folder of the sets' ``data:`` folders, not shipped; ``extra``:
    overrides of every run, ``run_set``);
    writes ``generalisation.csv`` and ``generalisation.md`` into ``out_dir`` after each set
    (a later failure loses nothing) and returns the long table (set, role, tracker,
    IDF1, HOTA, MOTA, n_seeds, failures)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    trajectories = trajectories_root()
    parts = []
    for s in sets:
        missing = missing_data(s, trajectories, data_root)
        if missing:
            print(f"[skip] {s.name}: {', '.join(map(str, missing))} absent")
            continue
        print(f"[run] {s.name} ({s.role}): {s.description}, seeds {list(s.seeds)}", flush=True)
        try:
            parts.append(run_set(s, trackers, out_dir / "runs" / s.name.replace(" ", "_"),
                                 trajectories, length, data_root, extra))
        except Exception as err:  # noqa: BLE001 - one set's failure must not lose the others
            print(f"[fail] {s.name}: {type(err).__name__}: {err}")
            continue
        table = pd.concat(parts, ignore_index=True)
        write(table, sets, out_dir)
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


# --------------------------------------------------------------------------- tables


def _cell(r) -> str:
    vals = [r[m] for m in METRICS]
    if all(isinstance(v, float) and math.isnan(v) for v in vals):
        return "failed"
    text = " / ".join(number(float(v)) for v in vals)
    return text + (" (!)" if r["failures"] else "")


def markdown(table: pd.DataFrame, sets: Sequence[EvalSet]) -> str:
    """The wide table: one row per tracker, one column per set (``IDF1 / HOTA / MOTA``),
    tuning sets marked ``T``, untouched ``U``; then the legend of the sets."""
    order = [s for s in sets if s.name in set(table["set"])]
    trackers = list(dict.fromkeys(table["tracker"]))
    head = ["tracker", *(f"{s.name} ({'T' if s.role == TUNING else 'U'})" for s in order)]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for t in trackers:
        cells = [t]
        for s in order:
            r = table[(table["set"] == s.name) & (table["tracker"] == t)]
            cells.append(_cell(r.iloc[0]) if len(r) else "")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Cells: COMBINED IDF1 / HOTA / MOTA (mean over the set's seeds); (!) = a "
              "failure recorded in that set's errors.txt. T = tuning set (a default or a "
              "tuned parameter was chosen on it), U = untouched (nothing was chosen on it).", ""]
    lines += ["| set | role | seeds | what |", "|---|---|---|---|"]
    for s in order:
        lines.append(f"| {s.name} | {s.role} | {', '.join(map(str, s.seeds))} | {s.description} |")
    return "\n".join(lines) + "\n"


def write(table: pd.DataFrame, sets: Sequence[EvalSet], out_dir: Path) -> None:
    """generalisation.csv at full precision (``--combine`` reads it back: a CSV rounded to
    4 decimals then rounded to 3 in the tables moved a cell by 0.001 where its fourth decimal
    was 5) and generalisation.md."""
    table.to_csv(out_dir / "generalisation.csv", index=False, lineterminator="\n")
    (out_dir / "generalisation.md").write_text(markdown(table, sets))


TABLE_HEADING = "## Latest table"


def with_table(doc: str, section: str) -> str:
    """``doc`` (docs/generalisation.md's text) with its table section replaced by ``section``
    (which starts with ``TABLE_HEADING``): the text before the heading and the hand-written
    reading after the table (from the next ``### `` heading on) are kept; a doc without the
    heading gets the section appended."""
    start = doc.find(TABLE_HEADING)
    if start < 0:
        return doc.rstrip("\n") + "\n\n" + section
    end = doc.find("\n### ", start)
    return doc[:start] + section.rstrip("\n") + "\n" + ("" if end < 0 else doc[end:])


def provenance() -> str:
    """Date and commit (with ``+dirty`` when the worktree has changes) of this run."""
    def git(*args: str) -> str:
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                  check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return ""

    commit = git("rev-parse", "--short", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+dirty"
    return f"{_dt.date.today().isoformat()}, commit {commit}"
