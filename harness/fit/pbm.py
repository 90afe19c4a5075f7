"""``python -m harness.fit pbm``: fit the PBM feature-difference models (PBM 2.2, Fig. 3).

For every annotated person visible in two consecutive frames, the five parts of its
ground-truth box are measured in both frames (``trackers.frontend.parts``) and the
absolute differences of the six features (eq. 11) are collected per feature and part.
Each of the 30 sets is fitted by a half-normal, or by a two-component folded Gaussian
mixture where that wins by BIC (the differences are not unimodal). The models are written
as YAML for ``conf/tracker/pbm.yaml``'s ``models.path``, and a PNG shows the fitted
densities over the histograms of the differences (the paper's Fig. 3).

Sources (any combination):
    --synthetic [NAME ...]   built-in synthetic scenarios (harness.datasets.synthetic)
    --mot ROOT               MOTChallenge folder(s) with frames and gt (harness.datasets.mot)

The foreground is the sequence's exact label image when it has one (synthetic scenes),
else the whole box (with a warning: area and perimeter then carry no information).

Example:
    python -m harness.fit pbm --synthetic --seed 1 --out models.yaml --plot models.png
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from trackers.frontend.parts import N_PARTS, PART_NAMES, PartFeatureExtractor, centroid_ratios
from trackers.layered.association import feature_differences
from trackers.layered.models import (
    FEATURES,
    FeatureModels,
    fit_difference_model,
    save_feature_models,
)

log = logging.getLogger(__name__)

MIN_SIGMA = {"area": 0.01, "perimeter": 0.01, "hsv": 0.01, "xyz": 0.01, "displacement": 0.003,
             "overlap": 0.01}
"""Smallest standard deviation per feature: exact synthetic data would otherwise give
degenerate, over-confident models."""


def collect_differences(sequences: Iterable, max_frames: int | None = None,
                        min_visibility: float = 0.7, bins: int = 4) -> dict[str, np.ndarray]:
    """Frame-to-frame part feature differences of annotated people (eq. 11).

    Args:
        sequences: ``harness.datasets.base.Sequence`` objects with ground truth and frames.
        max_frames: frames read per sequence (None = all).
        min_visibility: people below this visibility (when known) or flagged occluded are
            skipped: the models describe unoccluded matches.
        bins: histogram bins per channel (must match the tracker's ``histogram_bins``).
    Returns:
        {feature: (K, 5) differences}.
    """
    ex = PartFeatureExtractor(bins)
    out: dict[str, list[np.ndarray]] = {f: [] for f in FEATURES}
    for seq in sequences:
        if seq.gt is None:
            log.warning("%s: no ground truth, skipped", seq.info.name)
            continue
        table = seq.gt.table
        occluded = seq.gt.occluded
        prev: dict[int, object] = {}
        warned = False
        n = seq.info.length if max_frames is None else min(seq.info.length, max_frames)
        for k in range(1, n + 1):
            frame = seq.frame(k)
            if frame is None:
                log.warning("%s: no pixels, skipped", seq.info.name)
                break
            lab = seq.foreground(k)
            if lab is None and not warned:
                log.warning("%s: no foreground masks; the whole box counts as foreground",
                            seq.info.name)
                warned = True
            fg = None if lab is None else lab != 0
            rows = seq.gt.rows_of(k)
            keep = np.ones(len(rows), dtype=bool)
            if occluded is not None:
                keep &= ~occluded[rows]
            vis = table.visibility[rows] if hasattr(table, "visibility") else None
            if vis is not None:
                keep &= ~(np.isfinite(vis) & (vis < min_visibility))
            rows = rows[keep]
            ids = table.ids[rows].astype(np.int64)
            boxes = table.boxes[rows]
            ex.start(frame, fg)
            if len(rows) == 0:
                prev = {}
                continue
            cents = np.array([_centroid(fg, b) for b in boxes])
            al, be = centroid_ratios(boxes, cents)
            feats = ex.extract(boxes, al, be)
            cur = {}
            for i, pid in enumerate(ids):
                f = feats.take(i)
                cur[int(pid)] = f
                if int(pid) in prev:
                    d = feature_differences(prev[int(pid)], f)[0, 0]  # (6, 5)
                    for fi, name in enumerate(FEATURES):
                        out[name].append(d[fi])
            prev = cur
    return {f: np.array(v).reshape(-1, N_PARTS) for f, v in out.items()}


def _centroid(fg: np.ndarray | None, box: np.ndarray) -> np.ndarray:
    from trackers.layered.search import region_centroid

    return region_centroid(fg, box)


def fit_models(diffs: dict[str, np.ndarray], description: str = "") -> FeatureModels:
    """One model per feature and part (``fit_difference_model``)."""
    models = {}
    for f in FEATURES:
        d = diffs[f]
        if len(d) == 0:
            raise ValueError("no differences collected: the sequences hold no person seen in two frames")
        models[f] = [fit_difference_model(d[:, j], min_sigma=MIN_SIGMA[f]) for j in range(N_PARTS)]
    return FeatureModels(models, description)


def plot_models(models: FeatureModels, diffs: dict[str, np.ndarray], path: str | Path) -> None:
    """Histograms of the differences with the fitted densities (Fig. 3), 6 x 5 panels."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(FEATURES), N_PARTS, figsize=(3.0 * N_PARTS, 2.2 * len(FEATURES)))
    for i, f in enumerate(FEATURES):
        for j, part in enumerate(PART_NAMES):
            ax = axes[i, j]
            d = diffs[f][:, j]
            m = models.models[f][j]
            hi = max(float(np.quantile(d, 0.995)) if len(d) else 1.0, 4 * float(m.sigmas.max()) * 0.5, 1e-3)
            ax.hist(d, bins=40, range=(0, hi), density=True, color="0.75")
            x = np.linspace(0, hi, 200)
            ax.plot(x, m.pdf(x), color="C3", lw=1.5)
            ax.set_title(f"{f} / {part} ({m.kind}, n={len(d)})", fontsize=7)
            ax.tick_params(labelsize=6)
    fig.suptitle("PBM feature differences between consecutive frames and fitted densities")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m harness.fit pbm", description=__doc__.split("\n")[0])
    ap.add_argument("--synthetic", nargs="*", metavar="NAME", default=None,
                    help="synthetic scenarios (no names = the default suite)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the synthetic scenes")
    ap.add_argument("--length", type=int, default=150, help="frames per synthetic scene")
    ap.add_argument("--mot", nargs="*", default=[], metavar="ROOT", help="MOTChallenge folders")
    ap.add_argument("--max-frames", type=int, default=None, help="frames read per sequence")
    ap.add_argument("--min-visibility", type=float, default=0.7)
    ap.add_argument("--bins", type=int, default=4, help="histogram bins per channel")
    ap.add_argument("--out", required=True, help="output YAML")
    ap.add_argument("--plot", default=None, help="output PNG of the fitted densities (Fig. 3)")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    sequences = []
    sources = []
    if args.synthetic is not None:
        from harness.datasets.synthetic import DEFAULT_SCENARIOS, load_suite

        names = args.synthetic or list(DEFAULT_SCENARIOS)
        sequences += load_suite(names, seed=args.seed, length=args.length)
        sources.append(f"synthetic scenarios {', '.join(names)} (seed {args.seed}, {args.length} frames)")
    for root in args.mot:
        from harness.datasets.mot import load_mot

        sequences += load_mot(root)
        sources.append(f"MOT folder {root}")
    if not sequences:
        ap.error("give --synthetic and/or --mot")
    diffs = collect_differences(sequences, args.max_frames, args.min_visibility, args.bins)
    description = "fitted on " + "; ".join(sources)
    models = fit_models(diffs, description)
    header = (f"PBM feature-difference models (PBM 2.2), written by `python -m harness.fit pbm`.\n"
              f"{description}; {len(diffs['area'])} frame-to-frame differences per part;\n"
              f"histogram_bins {args.bins}, min visibility {args.min_visibility}.\n"
              "Each entry: a folded Gaussian mixture over |difference| (half_normal = one "
              "component with mean 0).")
    save_feature_models(models, args.out, header)
    log.info("wrote %s (%d differences per part)", args.out, len(diffs["area"]))
    for f in FEATURES:
        log.info("%-12s %s", f, " ".join(f"{m.kind[:4]}:{m.sigmas.max():.3f}" for m in models.models[f]))
    if args.plot:
        plot_models(models, diffs, args.plot)
        log.info("wrote %s", args.plot)
    return 0
