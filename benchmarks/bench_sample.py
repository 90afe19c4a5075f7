"""The shipped CAVIAR sample (MPEG) against the JPEG frames distributed with CAVIAR.

Optional material: the JPEG frames are not shipped (``--jpeg``, default
``../shared/data/CAVIAR-OneLeaveShop1cor``, the layout of the CAVIAR distribution's
``img1/``); without them this prints why and exits 0. It prints

  (a) frames: the mean and largest absolute difference between each decoded MPEG frame and
      its JPEG, and whether the MPEG decode written by OpenCV at JPEG quality 95 equals the
      JPEG byte for byte in pixels (it does for all 295 frames: the JPEGs are that decode);
  (b) detections: precision / recall of ``--detector`` (silhouette) on both;
  (c) tracking: the COMBINED HOTA / IDF1 / MOTA / IDs of every built tracker on both, with
      noisy ground-truth detections (miss 0.3; pixels only reach the trackers' appearance
      models) and with ``--detector`` detections (pixels reach the detector too), and, as a
      yardstick of how much a perturbation of that size moves the figures, on the JPEGs
      re-encoded at quality 90 (another ~1.4 grey levels from the JPEGs).

    python benchmarks/bench_sample.py
    python benchmarks/bench_sample.py --jpeg path/to/CAVIAR-OneLeaveShop1cor --skip-tracking
"""

from __future__ import annotations

import argparse
import logging
import tempfile
from pathlib import Path

import cv2
import numpy as np

from occbench.commands.detect import run_detection
from occbench.datasets.caviar import load_caviar
from occbench.config.paths import data_path
from occbench.pipeline.experiment import run_experiment
from occbench.config.build import compose_config

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = data_path("CAVIAR-OneLeaveShop1cor")
JPEG = ROOT.parent / "shared" / "data" / "CAVIAR-OneLeaveShop1cor"
COLUMNS = ("HOTA", "IDF1", "MOTA", "IDs")


def frames(jpeg: Path) -> None:
    (video,) = load_caviar(SHIPPED)
    (images,) = load_caviar(jpeg)
    diff, worst, same = [], 0, 0
    for (k, a), (_, b) in zip(video.frames(), images.frames(), strict=True):
        d = np.abs(a.astype(np.int16) - b.astype(np.int16))
        diff.append(d.mean())
        worst = max(worst, int(d.max()))
        buf = cv2.imencode(".jpg", a, [cv2.IMWRITE_JPEG_QUALITY, 95])[1]
        same += bool(np.array_equal(cv2.imdecode(buf, cv2.IMREAD_COLOR), b))
    print(f"(a) frames: {len(diff)} decoded; |MPEG - JPEG| mean {np.mean(diff):.3f} grey levels "
          f"(per frame {min(diff):.3f}-{max(diff):.3f}), largest {worst}; MPEG decode at JPEG "
          f"quality 95 equals the JPEG in {same} of {len(diff)} frames")


def detections(jpeg: Path, detector: str) -> None:
    print(f"(b) {detector} detections, IoU >= 0.5")
    for label, root in (("MPEG", SHIPPED), ("JPEG", jpeg)):
        cfg = compose_config(["dataset=caviar", f"dataset.root={root}", f"detector={detector}"],
                             config_name="detect")
        with tempfile.TemporaryDirectory() as tmp:
            row = run_detection(cfg, Path(tmp)).iloc[-1]
        print(f"  {label}: precision {row['precision']:.3f} recall {row['recall']:.3f} "
              f"F1 {row['F1']:.3f}")


def reencoded(jpeg: Path, out: Path, quality: int = 90) -> Path:
    """A copy of the CAVIAR folder ``jpeg`` whose img1/ frames are re-encoded at ``quality``."""
    import shutil

    shutil.copytree(jpeg / "gt", out / "gt")
    shutil.copy(jpeg / "seqinfo.ini", out / "seqinfo.ini")
    (out / "img1").mkdir()
    diffs = []
    for path in sorted((jpeg / "img1").glob("*.jpg")):
        img = cv2.imread(str(path))
        cv2.imwrite(str(out / "img1" / path.name), img, [cv2.IMWRITE_JPEG_QUALITY, quality])
        diffs.append(np.abs(cv2.imread(str(out / "img1" / path.name)).astype(np.int16) - img).mean())
    print(f"  JPEG q{quality} re-encode: |diff| from the JPEGs mean {np.mean(diffs):.3f} grey levels")
    return out


def tracking(jpeg: Path, detector: str) -> None:
    print("(c) tracking, COMBINED " + " / ".join(COLUMNS))
    tmp_root = Path(tempfile.mkdtemp(prefix="bench_sample_"))
    q90 = reencoded(jpeg, tmp_root / "CAVIAR-OneLeaveShop1cor")
    for det in (["detector=noisy_gt", "detector.miss_rate=0.3"], [f"detector={detector}"]):
        for label, root in (("MPEG", SHIPPED), ("JPEG", jpeg), ("JPEG q90", q90)):
            cfg = compose_config(["dataset=caviar", f"dataset.root={root}", *det])
            with tempfile.TemporaryDirectory() as tmp:
                m = run_experiment(cfg, tmp).metrics
            m = m[m["sequence"] == "COMBINED"].set_index("tracker")
            cells = "  ".join(f"{t} " + "/".join(f"{m.loc[t, c]:.3f}" if c != "IDs"
                                                  else f"{int(m.loc[t, c])}" for c in COLUMNS)
                              for t in m.index)
            print(f"  {det[0]:<18} {label}: {cells}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jpeg", type=Path, default=JPEG, help="CAVIAR folder with img1/ JPEGs")
    ap.add_argument("--detector", default="silhouette")
    ap.add_argument("--skip-tracking", action="store_true")
    args = ap.parse_args()
    if not (args.jpeg / "img1").is_dir():
        print(f"bench_sample: skipped: no JPEG frames at {args.jpeg / 'img1'} (optional material)")
        return 0
    logging.basicConfig(level=logging.WARNING)
    frames(args.jpeg)
    detections(args.jpeg, args.detector)
    if not args.skip_tracking:
        tracking(args.jpeg, args.detector)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
