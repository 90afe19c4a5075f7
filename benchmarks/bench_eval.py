"""Benchmark of scoring at MOT20 density: ``occbench eval`` against TrackEval 1.3.0.

Generates a case deterministically (seeded): by default 3,000 frames of 1920x1080 with 600
people, each on screen for about 490 frames (about 100 in each frame, about 294k gt boxes),
and a tracker result that finds 92 % of the boxes with jitter, breaks every person's track
into about 6.5 ids and adds about 14k false boxes in 50-frame tracks (about 4,200 result
ids); ``--false-ids`` gives every false box its own id instead (about 18k result ids). The
case is written as MOTChallenge files (``<tmp>/gt/<seq>/gt/gt.txt``, ``seqinfo.ini``,
``seqmap.txt``, ``<tmp>/tracks/bench/<seq>.txt``) and scored by whole processes, as a user
runs them: ``occbench eval GT RESULTS --csv`` and TrackEval's ``Evaluator`` on
``MotChallenge2DBox`` with HOTA, CLEAR and Identity (when importable; said when not). Each is
run ``--repeats`` times in turn; wall time, CPU time (user + system: steadier than wall time
on a shared machine) and peak memory (the child's own maximum resident set) are given as
medians, with the ratios TrackEval / occbench. The figures of both (every
column of ``occbench.metrics.COLUMNS`` on the COMBINED row) must agree to 1e-6.

The run's own scoring (``run_experiment`` -> ``score_sequence`` and ``extra_score``, the
paper and occlusion metrics) is timed in this process on the same tables.

Usage: ``python benchmarks/bench_eval.py [--frames 3000 --people 600] [--false-ids]
[--repeats 3] [--no-trackeval] [--keep DIR]``; ``--frames 300 --people 60`` runs in seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from occbench.io.mot import read_mot
from occbench.metrics import COLUMNS, score_sequence
from occbench.metrics.occlusion import extra_score

SEQ = "MOT20-density"
WIDTH, HEIGHT = 1920, 1080
TOLERANCE = 1e-6

TRACKEVAL_DRIVER = '''
import json, sys
import numpy as np
import trackeval

root, out = sys.argv[1], sys.argv[2]
quiet = {"PRINT_CONFIG": False}
evaluator = trackeval.Evaluator({"USE_PARALLEL": False, "PRINT_RESULTS": False,
    "PRINT_CONFIG": False, "TIME_PROGRESS": False, "OUTPUT_SUMMARY": False,
    "OUTPUT_DETAILED": False, "PLOT_CURVES": False, "DISPLAY_LESS_PROGRESS": True})
dataset = trackeval.datasets.MotChallenge2DBox({"GT_FOLDER": f"{root}/gt",
    "SEQMAP_FILE": f"{root}/gt/seqmap.txt", "SKIP_SPLIT_FOL": True,
    "TRACKERS_FOLDER": f"{root}/tracks", "TRACKER_SUB_FOLDER": "",
    "OUTPUT_FOLDER": f"{root}/trackeval", "TRACKERS_TO_EVAL": ["bench"], **quiet})
metrics = [trackeval.metrics.HOTA(quiet), trackeval.metrics.CLEAR(quiet),
           trackeval.metrics.Identity(quiet)]
res, _ = evaluator.evaluate([dataset], metrics)
r = res["MotChallenge2DBox"]["bench"]["COMBINED_SEQ"]["pedestrian"]
h, c, i = r["HOTA"], r["CLEAR"], r["Identity"]
figures = {k: float(np.mean(h[k])) for k in
           ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr")}
figures.update(MOTA=c["MOTA"], MOTP=c["MOTP"], Recall=c["CLR_Re"], Precision=c["CLR_Pr"],
               GT=c["MT"] + c["PT"] + c["ML"], MT=c["MT"], PT=c["PT"], ML=c["ML"],
               FP=c["CLR_FP"], FN=c["CLR_FN"], IDs=c["IDSW"], Frag=c["Frag"],
               IDF1=i["IDF1"], IDP=i["IDP"], IDR=i["IDR"])
with open(out, "w") as fh:
    json.dump({k: float(v) for k, v in figures.items()}, fh)
'''


def _reflect(x: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Fold positions into [0, hi] (walkers bounce off the image border)."""
    period = 2 * hi
    x = np.mod(x, period)
    return np.where(x > hi, period - x, x)


def make_case(frames: int, people: int, per_frame: float = 98.0, false_ids: bool = False,
              seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The gt rows (G, 6) and result rows (R, 6) ``frame, id, x, y, w, h`` (1-based frames,
    boxes xywh in pixels), sorted by frame then id."""
    rng = np.random.default_rng(seed)
    mean_len = min(frames, per_frame * frames / people)
    length = np.clip(rng.normal(mean_len, 0.15 * mean_len, people), 1, frames).astype(int)
    start = 1 + (rng.random(people) * (frames - length + 1)).astype(int)
    person = np.repeat(np.arange(people), length)
    t = np.arange(len(person)) - np.repeat(np.cumsum(length) - length, length)
    h = rng.uniform(80, 220, people)[person]
    w = 0.4 * h
    x = _reflect(rng.uniform(0, WIDTH, people)[person] + rng.uniform(-2, 2, people)[person] * t,
                 WIDTH - w)
    y = _reflect(rng.uniform(0, HEIGHT, people)[person]
                 + rng.uniform(-0.5, 0.5, people)[person] * t, HEIGHT - h)
    gt = np.column_stack([start[person] + t, person + 1, x, y, w, h])

    # result: 92 % found, jittered, each person's track broken into about 6.5 ids
    found = rng.random(len(gt)) < 0.92
    breaks = rng.poisson(5.5, people)
    cut = [np.sort(rng.integers(0, n, k)) for n, k in zip(length, breaks)]
    piece = np.concatenate([np.searchsorted(c, np.arange(n), side="right")
                            for c, n in zip(cut, length)])
    first_id = np.cumsum(breaks + 1) - (breaks + 1)
    ids = first_id[person] + piece + 1
    box = gt[:, 2:] + rng.normal(0, 0.04, (len(gt), 4)) * np.column_stack([w, h, w, h])
    box[:, 2:] = np.maximum(box[:, 2:], 4.0)
    res = [np.column_stack([gt[found, 0], ids[found], box[found]])]

    # false boxes, in 50-frame tracks (or one id each)
    n_tracks, run = round(0.048 * len(gt) / 50), 50
    f0 = rng.integers(1, max(2, frames - run + 2), n_tracks)
    fh = rng.uniform(80, 220, n_tracks)
    fx, fy = rng.uniform(0, WIDTH - 100, n_tracks), rng.uniform(0, HEIGHT - 230, n_tracks)
    k = np.repeat(np.arange(n_tracks), run)
    ft = np.tile(np.arange(run), n_tracks)
    keep = f0[k] + ft <= frames
    k, ft = k[keep], ft[keep]
    next_id = int(ids.max()) + 1
    fid = next_id + (np.arange(len(k)) if false_ids else k)
    res.append(np.column_stack([f0[k] + ft, fid, fx[k] + ft, fy[k], 0.4 * fh[k], fh[k]]))
    res = np.concatenate(res)
    return gt[np.lexsort((gt[:, 1], gt[:, 0]))], res[np.lexsort((res[:, 1], res[:, 0]))]


def write_case(root: Path, gt: np.ndarray, res: np.ndarray, frames: int) -> None:
    """MOTChallenge layout: gt with seqinfo.ini and seqmap.txt, results of tracker 'bench'."""
    seq = root / "gt" / SEQ
    (seq / "gt").mkdir(parents=True, exist_ok=True)
    (root / "gt" / "seqmap.txt").write_text(f"name\n{SEQ}\n")
    (seq / "seqinfo.ini").write_text(
        f"[Sequence]\nname={SEQ}\nimDir=img1\nframeRate=25\nseqLength={frames}\n"
        f"imWidth={WIDTH}\nimHeight={HEIGHT}\nimExt=.jpg\n")
    np.savetxt(seq / "gt" / "gt.txt", gt, fmt="%d,%d,%.2f,%.2f,%.2f,%.2f,1,1,1")
    (root / "tracks" / "bench").mkdir(parents=True, exist_ok=True)
    np.savetxt(root / "tracks" / "bench" / f"{SEQ}.txt", res,
               fmt="%d,%d,%.2f,%.2f,%.2f,%.2f,1,-1,-1,-1")


def timed(cmd: list[str], log: Path) -> tuple[float, float, float]:
    """Run ``cmd`` as a child process; (wall seconds, CPU seconds (user + system), peak
    resident MB) of the child. Never through a warm server (``occbench.server``): the child
    would only wait for the server's process, and its CPU and memory would not be the job's."""
    env = {**os.environ, "OCCBENCH_SERVER": "off"}
    with log.open("ab") as fh:
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=fh, stderr=fh, stdin=subprocess.DEVNULL, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed with exit status {proc.returncode}; see {log}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def occbench_figures(csv: Path) -> dict[str, float]:
    import pandas as pd

    row = pd.read_csv(csv).set_index("sequence").loc["COMBINED"]
    return {k: float(row[k]) for k in COLUMNS}


def compare(ours: dict[str, float], theirs: dict[str, float]) -> list[str]:
    """Columns whose figures differ by more than TOLERANCE (as 'name ours theirs')."""
    return [f"{k} {ours[k]!r} {theirs[k]!r}" for k in COLUMNS
            if not abs(ours[k] - theirs[k]) <= TOLERANCE]


def run_scoring(root: Path, repeats: int) -> dict[str, tuple[float, float]]:
    """Median (wall, CPU) seconds of the run's own scoring on the case, in this process."""
    gt = read_mot(root / "gt" / SEQ / "gt" / "gt.txt", gt=True)
    res = read_mot(root / "tracks" / "bench" / f"{SEQ}.txt", kind="result")
    out: dict[str, list[tuple[float, float]]] = {"score_sequence": [], "extra_score": []}
    for _ in range(repeats):
        for name, score in (("score_sequence", score_sequence), ("extra_score", extra_score)):
            wall, cpu = time.perf_counter(), time.process_time()
            score(gt, res)
            out[name].append((time.perf_counter() - wall, time.process_time() - cpu))
    return {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v))
            for k, v in out.items()}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=3000)
    p.add_argument("--people", type=int, default=600)
    p.add_argument("--per-frame", type=float, default=98.0, help="people in each frame")
    p.add_argument("--false-ids", action="store_true", help="one result id per false box")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-trackeval", action="store_true")
    p.add_argument("--keep", type=Path, default=None, help="write the case here and keep it")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_eval_") as tmp:
        root = args.keep or Path(tmp)
        gt, res = make_case(args.frames, args.people, args.per_frame, args.false_ids, args.seed)
        write_case(root, gt, res, args.frames)
        print(f"case: {args.frames} frames, {args.people} people, {len(gt)} gt boxes "
              f"({len(gt) / args.frames:.1f} a frame), {len(res)} result boxes, "
              f"{len(np.unique(res[:, 1]))} result ids; load {os.getloadavg()[0]:.1f}")
        print(run_comparison(root, args.repeats, not args.no_trackeval))
        print(f"load average after: {os.getloadavg()[0]:.1f}")
        times = run_scoring(root, args.repeats)
        print("run's own scoring, in process (median s, wall / CPU): " + ", ".join(
            f"{k} {w:.2f} / {c:.2f}" for k, (w, c) in times.items()))


def run_comparison(root: Path, repeats: int, with_trackeval: bool) -> str:
    """Time occbench eval (and TrackEval) in turn; the report's lines."""
    import shutil

    occbench = shutil.which("occbench")
    ours_cmd = ([occbench] if occbench else [sys.executable, "-m", "occbench"]) + [
        "eval", str(root / "gt"), str(root / "tracks" / "bench"), "--csv", str(root / "ours.csv")]
    te_cmd = None
    if with_trackeval:
        try:
            import trackeval  # noqa: F401
        except ImportError:
            print("TrackEval is not importable: occbench eval timed alone "
                  "(pip install --no-deps trackeval==1.3.0 pycocotools tabulate)")
        else:
            driver = root / "trackeval_driver.py"
            driver.write_text(TRACKEVAL_DRIVER)
            te_cmd = [sys.executable, str(driver), str(root), str(root / "trackeval.json")]
    ours, theirs = [], []
    for _ in range(repeats):
        ours.append(timed(ours_cmd, root / "occbench.log"))
        if te_cmd:
            theirs.append(timed(te_cmd, root / "trackeval.log"))
    o = [statistics.median(x) for x in zip(*ours)]
    lines = [(f"occbench eval: {o[0]:.2f} s wall, {o[1]:.2f} s CPU, {o[2]:.0f} MB peak "
              f"(medians of {repeats})")]
    if te_cmd:
        t = [statistics.median(x) for x in zip(*theirs)]
        lines.append(f"TrackEval 1.3.0: {t[0]:.2f} s wall, {t[1]:.2f} s CPU, {t[2]:.0f} MB peak "
                     f"(medians of {repeats})")
        lines.append(f"TrackEval / occbench: wall {t[0] / o[0]:.2f}x, CPU {t[1] / o[1]:.2f}x, "
                     f"peak memory {t[2] / o[2]:.2f}x")
        theirs_fig = json.loads((root / "trackeval.json").read_text())
        differ = compare(occbench_figures(root / "ours.csv"), theirs_fig)
        lines.append(f"figures agree to {TOLERANCE:g}: {'yes' if not differ else 'NO'}")
        lines.extend(f"  differs: {d}" for d in differ)
    return "\n".join(lines)


if __name__ == "__main__":
    main()
