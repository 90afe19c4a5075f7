"""``occbench fit silhouette``: learn the mean person mask of the silhouette detector.

For every ``--step``-th frame of the sequences named by the Hydra overrides, each gt person
that is (nearly) fully visible and does not touch another person's box gives one mask,
cropped to its box: the exact label image (``sequence.foreground(k) == id``) where the
dataset has one (synthetic scenes), else the front end's foreground mask (the
``--detector`` config's background model, warmed up on the sequence) inside the box. The
template is the mean of the masks resized to a common size (``silhouette.fit_template``).

The shipped ``trackers/frontend/data/silhouette.npy`` was made by
``occbench fit silhouette dataset=synthetic`` (exact masks of rendered walkers;
no frame of a benchmark sequence is used).

Example: ``occbench fit silhouette dataset=synthetic --out my_template.npy``
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np
from hydra.utils import instantiate

from occbench.config.build import compose_config
from occbench.progress import log_to_stderr
from occbench.trackers.frontend.silhouette_template import TEMPLATE_HEIGHT, fit_template
from occbench.trackers.geometry import intersection_matrix

log = logging.getLogger(__name__)

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "trackers" / "frontend" / "data" / "silhouette.npy"


def person_masks(sequences, step: int = 5, min_visibility: float = 0.95, min_height: float = 24.0,
                 background=None) -> list[np.ndarray]:
    """Box-cropped single-person masks (bool arrays) from annotated sequences."""
    masks: list[np.ndarray] = []
    for seq in sequences:
        if seq.gt is None or not seq.has_pixels:
            log.warning("%s: no ground truth or no pixels, skipped", seq.info.name)
            continue
        table = seq.gt.table
        bg = None
        if seq.foreground(1) is None:
            if background is None:
                log.warning("%s: no label images and no background model, skipped", seq.info.name)
                continue
            bg = background
            bg.reset()
            bg.warm_up_sequence(seq.info.length, seq.nth_frame)
        for k in seq.frame_numbers():
            fg = None
            if bg is not None:
                fg = bg.apply(seq.frame(k))  # every frame updates the model
            if (k - 1) % step:
                continue
            rows = seq.gt.rows_of(k)
            if len(rows) == 0:
                continue
            labels = seq.foreground(k) if bg is None else None
            boxes = table.boxes[rows]
            inter = intersection_matrix(boxes, boxes)
            np.fill_diagonal(inter, 0.0)
            H, W = (labels if labels is not None else fg).shape
            for j, r in enumerate(rows):
                x, y, w, h = boxes[j]
                vis = table.visibility[r]
                if h < min_height or inter[j].any():
                    continue
                if np.isfinite(vis) and vis < min_visibility:
                    continue
                if seq.gt.occluded is not None and seq.gt.occluded[r]:
                    continue
                r0, c0 = round(y), round(x)
                r1, c1 = round(y + h), round(x + w)
                if r0 < 0 or c0 < 0 or r1 > H or c1 > W:  # cut by the image border
                    continue
                crop = (labels[r0:r1, c0:c1] == table.ids[r]) if labels is not None else fg[r0:r1, c0:c1]
                if crop.mean() > 0.2:
                    masks.append(crop)
    return masks


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="occbench fit silhouette", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("overrides", nargs="*", help="Hydra overrides, e.g. dataset=synthetic")
    ap.add_argument("--out", type=Path, required=True,
                    help=f"output .npy (required: the shipped one is {DEFAULT_OUT}, tracked; "
                         "name it to replace it)")
    ap.add_argument("--step", type=int, default=5, help="use every step-th frame")
    ap.add_argument("--height", type=int, default=TEMPLATE_HEIGHT, help="template rows")
    ap.add_argument("--min-visibility", type=float, default=0.95)
    ap.add_argument("--detector", default="silhouette",
                    help="detector config whose background model makes masks where the "
                         "dataset has no label images")
    args = ap.parse_args(argv)
    log_to_stderr()

    overrides = list(args.overrides) or ["dataset=synthetic"]
    cfg = compose_config([*overrides, f"detector={args.detector}"])
    sequences = list(instantiate(cfg.dataset))
    background = instantiate(cfg.detector.detector.background)
    masks = person_masks(sequences, step=args.step, min_visibility=args.min_visibility,
                         background=background)
    if not masks:
        raise SystemExit("no single-person masks found in " + " ".join(overrides))
    template = fit_template(masks, height=args.height)
    out = args.out
    out.parent.mkdir(parents=True, exist_ok=True)
    np.save(out, template)
    log.info("wrote %s: %s template from %d masks", out, template.shape, len(masks))
    return 0
