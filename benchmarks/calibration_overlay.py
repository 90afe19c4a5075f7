"""The scene calibration the silhouette detector learns on unlabelled videos (by eye, no score).

For each video: the default front end (``detector=silhouette``) warms up on it, which learns
the perspective line (``occbench.trackers.frontend.calibration``: expected person height against the
foot row), then runs to a chosen frame. The picture shows that frame with the foreground
tinted, the detector's boxes, and the expected person box the learnt line gives at every
40th foot row (or a note that the calibration fell back to searching every height).

Run: ``python benchmarks/calibration_overlay.py [--videos V1 V2 ...] [--frame 120]
[--out docs/img/calibration_unlabelled.png]`` (default: the three unlabelled CAVIAR videos
in ``../shared/data/videos/``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from occbench.config.build import compose_config  # noqa: E402
from occbench.report.draw import grid  # noqa: E402
from occbench.report.primitives import legend_strip  # noqa: E402

VIDEOS = ROOT.parent / "shared" / "data" / "videos"
DEFAULT = ["CAVIAR-ShopAssistant1cor.mp4", "CAVIAR-OneStopEnter1front.mp4",
           "CAVIAR-OneStopMoveNoEnter1front.mp4"]
EXPECTED, DETECTED, FOREGROUND = (0, 215, 255), (0, 200, 0), (255, 80, 80)  # BGR


def panel(video: Path, at: int) -> np.ndarray:
    """Frame ``at`` of ``video`` drawn with the calibration learnt on it and the detections."""
    from hydra.utils import instantiate

    cfg = compose_config(["dataset=video", f"dataset.path={video}", "detector=silhouette"])
    seq = next(iter(instantiate(cfg.dataset)))
    source = instantiate(cfg.detector, _convert_="all")
    source.start(seq)  # background warm-up and scene calibration
    at = min(at, seq.info.length)
    for k in range(1, at + 1):
        frame = seq.frame(k)
        dets, fg = source.detect(k, frame)
    img = frame.copy()
    if fg is not None:
        tint = img.copy()
        tint[fg > 0] = FOREGROUND
        img = cv2.addWeighted(img, 0.6, tint, 0.4, 0)
    perspective = source.detector.perspective
    H, W = img.shape[:2]
    if perspective is None:
        text = "too little evidence: every height searched"
    else:
        text = f"height = {perspective.a:.3f} * foot row {perspective.b:+.1f} ({perspective.samples} samples)"
        for i, foot in enumerate(range(H - 1, 0, -40)):
            h, w = float(perspective.height(foot)), float(perspective.width(foot))
            if h < 8:
                break
            x = (i % 4 + 0.5) * W / 4 - w / 2  # spread across the width so boxes do not stack
            cv2.rectangle(img, (round(x), round(foot - h)), (round(x + w), foot), EXPECTED, 1)
    for x, y, w, h in dets.boxes:
        cv2.rectangle(img, (round(x), round(y)), (round(x + w), round(y + h)), DETECTED, 1)
    caption = np.full((40, W, 3), 255, np.uint8)
    for line, words in enumerate((f"{video.stem.removeprefix('CAVIAR-')}, frame {at}", text)):
        cv2.putText(caption, words, (5, 15 + 18 * line), cv2.FONT_HERSHEY_SIMPLEX, 0.42,
                    (0, 0, 0), 1)
    return np.vstack([img, caption])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--videos", type=Path, nargs="+", default=[VIDEOS / v for v in DEFAULT])
    ap.add_argument("--frame", type=int, default=120, help="frame drawn (1-based)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "calibration_unlabelled.png")
    args = ap.parse_args(argv)
    missing = [str(v) for v in args.videos if not v.is_file()]
    if missing:
        raise SystemExit(f"video(s) not found: {', '.join(missing)}")
    row = grid([panel(v, args.frame) for v in args.videos])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    legend = legend_strip([("expected person at that foot row (learnt line)", EXPECTED),
                           ("detections", DETECTED), ("foreground", FOREGROUND)], row.shape[1])
    cv2.imwrite(str(args.out), np.vstack([legend, row]))
    print(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
