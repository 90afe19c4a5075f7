"""Front-end benchmark: (a) detection quality on CAVIAR, (b) speed per stage on one core.

(a) Reta et al. 2015, section 4.2 layout: person detections of every frame of
    CAVIAR OneLeaveShop1cor against its ground truth (all annotated people, one-to-one
    Hungarian matching at IoU >= 0.5), precision / recall / F1 for the silhouette and
    foreground detectors and for OpenCV's HOG+SVM, over all frames and over the held-out
    half (frames 151-295: ``conf/detector/silhouette_caviar.yaml`` was calibrated and tuned
    on frames 1-150 only). The paper reports, over its CAVIAR sequences, 87% precision /
    62% recall for its detector and 51% / 43% for HOG-SVM.
(b) Frames per second of each stage with ``cv2.setNumThreads(1)``: JPEG decode, background
    model, morphology (shadow removal, open, close), blobs, each detector, appearance
    features (ellipse histograms of the detections), at 384x288 (CAVIAR) and 768x576
    (CAVIAR upscaled 2x). Targets for the foreground path (decode to blobs): 250 frames/s at
    384x288 and 80 frames/s at 768x576.

Run: ``python benchmarks/bench_frontend.py [--frames N] [--skip-quality] [--skip-speed]``.
Reads the shipped CAVIAR-OneLeaveShop1cor (``occbench.config.paths``, $OCCBENCH_DATA moves it); exits with a message
when it is absent.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra.utils import instantiate

from occbench.commands.detect import match_count, run_detection
from occbench.io.mot import read_mot
from occbench.config.paths import data_path
from occbench.config.build import compose_config
from occbench.trackers.frontend.blobs import blobs_from_mask
from occbench.trackers.three_hypothesis.features import ellipse_histograms

CAVIAR = data_path("CAVIAR-OneLeaveShop1cor")

#: (label, detector config, overrides) compared in (a)
QUALITY = [
    ("silhouette (ours, self-calibrated, default)", "silhouette", []),
    ("ORACLE: silhouette + gt calibration (1-150)", "silhouette_caviar", []),
    ("foreground blobs + head split", "foreground", []),
    ("HOG+SVM on foreground, person box", "hog", []),
    ("HOG+SVM on foreground, raw 64x128 window", "hog", ["detector.detector.boxes.box_scale=[1.0,1.0]"]),
    ("HOG+SVM whole frame, person box", "hog", ["detector.detector.crops.full_frame=true"]),
]
PAPER = [("Reta et al. 2015 detector (paper)", 0.87, 0.62), ("HOG-SVM (paper)", 0.51, 0.43)]


#: first frame of the held-out half of CAVIAR OneLeaveShop1cor (calibration used 1-150)
HELD_OUT = 151


def _held_out(det_path: Path, seq) -> tuple[float, float]:
    """Precision and recall of a written det file over frames >= HELD_OUT."""
    det = read_mot(det_path)
    di, gi = det.frame_index(), seq.gt.table.frame_index()
    tp = nd = ng = 0
    for k in range(HELD_OUT, seq.info.length + 1):
        rows = gi.get(k, np.zeros(0, dtype=np.int64))
        rows = rows[seq.gt.table.conf[rows] > 0]
        gt = seq.gt.table.boxes[rows]
        boxes = det.boxes[di.get(k, np.zeros(0, dtype=np.int64))]
        tp += match_count(gt, boxes)
        nd, ng = nd + len(boxes), ng + len(gt)
    return (tp / nd if nd else float("nan")), (tp / ng if ng else float("nan"))


def quality() -> None:
    print("(a) detection quality, CAVIAR OneLeaveShop1cor, IoU >= 0.5: all 295 frames, "
          f"and frames {HELD_OUT}-295 (held out)")
    print(f"{'detector':<44} {'prec':>6} {'recall':>6} {'F1':>6} {'dets':>6} {'TP':>6} {'gt':>6}"
          f" {'P held':>7} {'R held':>7}")
    for label, p, r in PAPER:
        print(f"{label:<44} {p:6.3f} {r:6.3f} {2 * p * r / (p + r):6.3f} {'':>6} {'':>6} {'':>6}")
    seq = None
    for label, name, extra in QUALITY:
        cfg = compose_config(["dataset=caviar", f"dataset.root={CAVIAR}", f"detector={name}",
                              "dataset.prefetch=0", *extra], config_name="detect")
        if seq is None:
            seq = next(iter(instantiate(cfg.dataset)))
        with tempfile.TemporaryDirectory() as tmp:
            row = run_detection(cfg, Path(tmp)).iloc[-1]
            ph, rh = _held_out(Path(tmp) / "det" / f"{seq.info.name}.txt", seq)
        print(f"{label:<44} {row.precision:6.3f} {row.recall:6.3f} {row.F1:6.3f} "
              f"{int(row['detections']):6d} {int(row['TP']):6d} {int(row['gt']):6d}"
              f" {ph:7.3f} {rh:7.3f}")


def _timed(fn, *args):
    t0 = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - t0


def speed(n_frames: int) -> None:
    cv2.setNumThreads(1)
    from occbench.datasets.caviar import load_caviar

    (seq,) = load_caviar(CAVIAR)
    originals = [img for k, img in seq.frames() if k <= n_frames]
    print(f"\n(b) speed, one core (cv2.setNumThreads(1)), {len(originals)} CAVIAR frames, "
          "frames/s per stage (mean time per frame in ms)")
    stages = ("decode", "background", "background x0.5", "morphology", "blobs", "foreground det",
              "silhouette det", "hog det", "features")
    rows = {}
    for scale in (1, 2):
        jpegs = []
        for img in originals:
            if scale != 1:
                img = cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_LINEAR)
            jpegs.append(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 90])[1])
        frames = [cv2.imdecode(j, cv2.IMREAD_COLOR) for j in jpegs]
        h, w = frames[0].shape[:2]
        size: list[str] = []
        k = scale  # detector sizes scale with the frame
        dets = {}
        for name, extra in (("foreground", [f"detector.detector.blobs.min_area={80 * k * k}",
                                             f"detector.detector.blobs.min_height={20 * k}"]),
                            ("silhouette", [f"detector.detector.matcher.search.downscale={2 * k}"]),
                            ("hog", [f"detector.detector.crops.min_blob_area={60 * k * k}"])):
            cfg = compose_config([f"detector={name}", *size, *extra], config_name="detect")
            dets[name] = instantiate(cfg.detector).detector
        bg = dets["foreground"].background
        half = instantiate(compose_config(
            ["detector=foreground", *size, "detector.detector.background.frames.work_scale=0.5"],
            config_name="detect").detector).detector.background
        for model in (bg, half):  # learn the background first (not timed)
            model.warm_up_sequence(len(frames), lambda i, fr=frames: fr[i - 1])
        t = dict.fromkeys(stages, 0.0)
        for i, jpg in enumerate(jpegs):
            frame, dt = _timed(cv2.imdecode, jpg, cv2.IMREAD_COLOR)
            t["decode"] += dt
            raw, dt = _timed(bg.raw, frame)
            t["background"] += dt
            _, dt = _timed(half.raw, frame)
            t["background x0.5"] += dt
            clean, dt = _timed(bg.clean, raw)
            t["morphology"] += dt
            fg = clean > 0
            blobs, dt = _timed(blobs_from_mask, fg, dets["foreground"].blobs.min_area)
            t["blobs"] += dt
            _d, dt = _timed(dets["foreground"].detect_on, frame, fg, blobs)
            t["foreground det"] += dt
            sd, dt = _timed(dets["silhouette"].detect_on, frame, fg)
            t["silhouette det"] += dt
            if i % 5 == 0:  # HOG is slow: every fifth frame, scaled up below
                _, dt = _timed(dets["hog"].detect_on, frame, fg)
                t["hog det"] += 5 * dt
            _, dt = _timed(ellipse_histograms, frame, sd.boxes, fg)
            t["features"] += dt
        n = len(jpegs)
        rows[f"{w}x{h}"] = {s: t[s] / n for s in stages}
        path = sum(t[s] for s in ("decode", "background", "morphology", "blobs")) / n
        rows[f"{w}x{h}"]["foreground path"] = path
        rows[f"{w}x{h}"]["  with background x0.5"] = (
            path + (t["background x0.5"] - t["background"]) / n)
    cols = list(rows)
    print(f"{'stage':<22}" + "".join(f"{c:>22}" for c in cols))
    for s in (*stages, "foreground path", "  with background x0.5"):
        print(f"{s:<22}" + "".join(
            f"{1.0 / max(rows[c][s], 1e-9):>12.0f} ({1000 * rows[c][s]:5.2f} ms)" for c in cols))
    print("targets, foreground path (decode, background, morphology, blobs): 250 frames/s at "
          "384x288, 80 at 768x576; 'background x0.5' runs the model at half resolution "
          "(detector.detector.background.frames.work_scale=0.5)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=150, help="frames timed per size")
    ap.add_argument("--skip-quality", action="store_true")
    ap.add_argument("--skip-speed", action="store_true")
    args = ap.parse_args()
    if not CAVIAR.is_dir():
        print(f"bench_frontend: CAVIAR data not found at {CAVIAR} (set OCCBENCH_DATA); skipped")
        return 0
    if not args.skip_quality:
        quality()
    if not args.skip_speed:
        speed(args.frames)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
