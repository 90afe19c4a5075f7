"""``occbench fit heads``: fit the head detector's hair and skin mixtures (PBM 2.3).

Two sources of pixels:

* ``--references``: samples around reference hair and skin colours
  (``occbench.trackers.frontend.heads.REFERENCE_RGB``), seeded; this is how the shipped default
  ``trackers/frontend/data/heads.npz`` was made.
* Hydra overrides naming a dataset with ground truth (e.g. ``dataset=synthetic``): in every
  ``--step``-th frame, the head box of each gt person (the sequence's own head boxes when it
  provides ``head_boxes(k)``, else the top ``1/7`` of the gt box, central 60% of its width;
  restricted to the person's exact mask when the sequence has ``foreground(k)``) gives head
  pixels. Each pixel is assigned to its most likely category under the current model
  (``--init``, default: the shipped mixtures) and every category with at least
  ``--min-pixels`` pixels is refitted by EM; the others keep their current parameters.

Example: ``occbench fit heads dataset=synthetic --out heads.npz``
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np

from occbench.config.build import dataset_sequences
from occbench.progress import log_to_stderr
from occbench.trackers.frontend.heads import (
    HAIR,
    SKIN,
    ColourMixtures,
    category_likelihoods,
    fit_colour_mixtures,
    reference_samples,
)

log = logging.getLogger(__name__)

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "trackers" / "frontend" / "data" / "heads.npz"


def head_pixels_of(sequences, step: int = 5, head_fraction: float = 1 / 7) -> np.ndarray:
    """(N, 3) uint8 BGR pixels of the annotated heads of ``sequences``."""
    out: list[np.ndarray] = []
    for seq in sequences:
        if seq.gt is None or not seq.has_pixels:
            log.warning("%s: no ground truth or no pixels, skipped", seq.info.name)
            continue
        table = seq.gt.table
        for k in seq.frame_numbers()[::step]:
            rows = seq.gt.rows_of(k)
            if len(rows) == 0:
                continue
            frame = seq.frame(k)
            fg = seq.foreground(k)
            heads_fn = getattr(seq, "head_boxes", None)
            heads = heads_fn(k) if heads_fn is not None else None
            for j, r in enumerate(rows):
                if seq.gt.occluded is not None and seq.gt.occluded[r]:
                    continue
                x, y, w, h = table.boxes[r]
                if heads is not None and j < len(heads) and np.isfinite(heads[j]).all():
                    x, y, w, h = heads[j]
                else:
                    x, w, h = x + 0.2 * w, 0.6 * w, head_fraction * h
                r0, r1 = max(int(y), 0), min(int(np.ceil(y + h)), frame.shape[0])
                c0, c1 = max(int(x), 0), min(int(np.ceil(x + w)), frame.shape[1])
                if r1 <= r0 or c1 <= c0:
                    continue
                keep = np.ones((r1 - r0, c1 - c0), dtype=bool)
                if fg is not None:
                    keep = fg[r0:r1, c0:c1] == table.ids[r]
                out.append(frame[r0:r1, c0:c1][keep])
    return np.concatenate(out) if out else np.zeros((0, 3), dtype=np.uint8)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="occbench fit heads", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("overrides", nargs="*", help="Hydra overrides, e.g. dataset=synthetic")
    ap.add_argument("--references", action="store_true",
                    help="fit from samples around reference colours (the shipped default)")
    ap.add_argument("--out", type=Path, required=True,
                    help=f"output .npz (required: the shipped one is {DEFAULT_OUT}, tracked; "
                         "name it to replace it)")
    ap.add_argument("--init", type=Path, default=None, help="starting mixtures (.npz)")
    ap.add_argument("--components", type=int, default=2, help="Gaussians per channel mixture")
    ap.add_argument("--step", type=int, default=5, help="use every step-th frame")
    ap.add_argument("--min-pixels", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    log_to_stderr()
    out = args.out
    if args.references or not args.overrides:
        mix = fit_colour_mixtures(
            reference_samples(seed=args.seed), k=args.components,
            provenance=(
                f"EM fit (k={args.components}) to seeded samples (seed {args.seed}) around "
                "reference hair and skin colours (occbench.trackers.frontend.heads.REFERENCE_RGB), by "
                "`occbench fit heads --references`"
            ),
        )
    else:
        sequences = dataset_sequences(args.overrides)
        pixels = head_pixels_of(sequences, step=args.step)
        if len(pixels) == 0:
            raise SystemExit("no annotated head pixels found in " + " ".join(args.overrides))
        init = ColourMixtures.load(args.init)
        p = category_likelihoods(pixels.reshape(-1, 1, 3), init.tables(), 0.5, 0.5)[:, :, 0]
        best = p.argmax(axis=0)
        samples: dict[str, np.ndarray] = {}
        refs = reference_samples(seed=args.seed)
        for i, name in enumerate(init.names):
            mine = pixels[best == i]
            log.info("category %-8s: %d pixels", name, len(mine))
            samples[name] = mine if len(mine) >= args.min_pixels else refs[name]
        mix = fit_colour_mixtures(
            samples, k=args.components,
            provenance=(
                f"EM fit (k={args.components}) to {len(pixels)} annotated head pixels of "
                f"{' '.join(args.overrides)} assigned to categories by the initial model; "
                f"categories with < {args.min_pixels} pixels from reference colours"
            ),
        )
    assert set(mix.names) == set(HAIR + SKIN)
    out.parent.mkdir(parents=True, exist_ok=True)
    mix.save(out)
    log.info("wrote %s", out)
    return 0
