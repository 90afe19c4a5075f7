"""What the active-basis shape verifier changes on an unlabelled video (by eye, no score).

Runs ``detector=silhouette`` and ``detector=silhouette_shape`` over the first frames of a
video and draws chosen frames: boxes both keep (green), boxes only the shape verifier's
proposals add (red: people on foreground no fitted box explains) and boxes it drops
(magenta: a score under its threshold).

Run: ``python benchmarks/active_basis_overlay.py [--video ../shared/data/videos/CAVIAR-ShopAssistant1cor.mp4]
[--frames 30 50 120 200] [--out docs/img/active_basis_unlabelled.png]``.
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
from occbench.report.primitives import legend_strip  # noqa: E402
from occbench.trackers.geometry import iou_matrix  # noqa: E402

GREEN, RED, MAGENTA = (0, 200, 0), (0, 0, 255), (255, 0, 255)


def detections(video: Path, detector: str, last: int) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Boxes (xywh, 0-based) per frame 1..last, and the frames themselves."""
    from hydra.utils import instantiate

    cfg = compose_config(["dataset=video", f"dataset.path={video}", f"dataset.frames=[1,{last}]",
                          f"detector={detector}"])
    seq = next(iter(instantiate(cfg.dataset)))
    source = instantiate(cfg.detector, _convert_="all")
    source.start(seq)
    boxes, frames = {}, {}
    for k in seq.frame_numbers():
        frame = seq.frame(k)
        boxes[k] = source.detect(k, frame)[0].boxes
        frames[k] = frame
    return boxes, frames


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--video", type=Path, default=ROOT.parent / "shared" / "data" / "videos"
                    / "CAVIAR-ShopAssistant1cor.mp4")
    ap.add_argument("--frames", type=int, nargs="+", default=[30, 50, 120, 200])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "active_basis_unlabelled.png")
    args = ap.parse_args(argv)
    if not args.video.is_file():
        raise SystemExit(f"video not found: {args.video}")
    last = max(args.frames)
    plain, frames = detections(args.video, "silhouette", last)
    shape, _ = detections(args.video, "silhouette_shape", last)
    tiles = []
    for k in args.frames:
        img = frames[k].copy()
        a, b = plain[k], shape[k]
        both = iou_matrix(a, b) >= 0.5 if len(a) and len(b) else np.zeros((len(a), len(b)), bool)
        for boxes, matched, colour in ((a, both.any(axis=1), MAGENTA), (b, both.any(axis=0), RED)):
            for (x, y, w, h), m in zip(boxes, matched):
                cv2.rectangle(img, (round(x), round(y)), (round(x + w), round(y + h)), GREEN if m else colour, 1)
        cv2.putText(img, f"{args.video.stem} frame {k}", (6, img.shape[0] - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1)
        tiles.append(img)
    while len(tiles) % 2:
        tiles.append(np.zeros_like(tiles[0]))
    grid = np.vstack([np.hstack(tiles[i : i + 2]) for i in range(0, len(tiles), 2)])
    legend = legend_strip([("both detectors", GREEN), ("added (shape proposal)", RED),
                           ("dropped (shape score)", MAGENTA)], grid.shape[1])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out), np.vstack([legend, grid]))
    print(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
