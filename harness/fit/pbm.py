"""``python -m harness.fit pbm``: fit the PBM feature-difference models (PBM 2.2, Fig. 3)
and learn the feature weights omega of eq. 12 (PBM 4.1).

Models. For every annotated person visible in two consecutive frames, the five parts of
its ground-truth box are measured in both frames (``trackers.layered.parts``) and the
absolute differences of the six features (eq. 11) are collected per feature and part.
With the tracker config's ``adaptations.motion_compensation`` (the default), overlap and
displacement compare the person with its previous parts moved by its previous step, as the
tracker compares a candidate with the parts model moved by KF1's prediction. Each of the 30
sets is fitted by a half-normal, or by a two-component folded Gaussian mixture where that
wins by BIC (the differences are not unimodal).

Weights (PBM 4.1: "The weights in (12), omega_i, have been trained with maximum
cross-validation accuracy by a search over interval [0,1] and normalized to add up to 1").
Samples are pairs of consecutive frames: positive = a person against itself in the next
frame (the pairs the models are fitted on); negative = a person against up to
``--neighbours`` other people of the next frame whose box centre lies within ``--radius``
x its previous box width / height of its previous centre (the tracker's gate, PBM 3). Each
pair is scored as the tracker scores it: eq. 11 differences divided by
``adaptations.model_spread``, match probabilities p(d_ij | theta_ij) of the fitted models,
eq. 12 with omega, eq. 13 with the configured gamma (``features.part_weights``), and
classified as a match when the global score reaches ``matching.match_threshold``. omega runs
over a grid of [0, 1]^6 with step
``--weight-step`` (normalised to sum 1, all-zero skipped, duplicates after normalising
merged); the accuracy (balanced: positives and negatives weigh half each) is
cross-validated over ``--folds`` folds of whole frame blocks (``--block-frames`` frames of
one sequence), so neighbouring frames do not leak between training and validation. The
omega with the best mean validation accuracy wins; ties go to the one nearest the uniform
weights, then to the first in grid order. gamma, threshold and spread are read from
``--tracker-config`` (default ``conf/tracker/pbm.yaml``).

The YAML (for ``conf/tracker/pbm.yaml``'s ``features.models.path``) holds the models and, as
extra top-level keys that the model loader ignores, ``feature_weights`` and
``feature_weights_fit`` (accuracies, grid, folds, sample counts). A PNG shows the fitted
densities over the histograms of the differences (the paper's Fig. 3).

Sources (any combination):
    --synthetic [NAME ...]   built-in synthetic scenarios (harness.datasets.synthetic)
    --mot ROOT               MOTChallenge folder(s) with frames and gt (harness.datasets.mot)

The foreground is the sequence's exact label image when it has one (synthetic scenes),
else the whole box (with a warning: area and perimeter then carry no information).

Example:
    python -m harness.fit pbm --synthetic --seed 1 --out models.yaml --plot models.png

Using the learned weights (the command prints the exact line):
    python -m harness tracker.pbm.features.models.path=models.yaml \\
        'tracker.pbm.features.feature_weights={area:0.2,perimeter:0.0,hsv:0.2,xyz:0.4,displacement:0.2,overlap:0.0}'
(``tracker.features.feature_weights=...`` when the run selects ``tracker=pbm`` alone.)
Measured on held-out data, the omega learned on synthetic seed 1 tracks worse than the
hand-set default although it classifies held-out pairs better: see
``benchmarks/bench_pbm_weights.py``.
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from trackers.layered.association import feature_differences
from trackers.layered.feature_models import (
    FeatureModels,
    fit_difference_model,
)
from trackers.layered.parts import (
    FEATURES,
    N_PARTS,
    PART_NAMES,
    PartFeatureExtractor,
    centroid_ratios,
)

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
TRACKER_CONFIG = ROOT / "conf" / "tracker" / "pbm.yaml"

MIN_SIGMA = {"area": 0.01, "perimeter": 0.01, "hsv": 0.01, "xyz": 0.01, "displacement": 0.003,
             "overlap": 0.01}
"""Smallest standard deviation per feature: exact synthetic data would otherwise give
degenerate, over-confident models."""


@dataclass
class PairSamples:
    """Pairs (a person in frame k-1, a person in frame k) of annotated sequences.

    Attributes:
        d: (M, 6, 5) float64 eq. 11 differences (``FEATURES`` order, ``PART_NAMES`` order).
        positive: (M,) bool, True when both sides are the same person.
        block: (M,) int64 id of the frame block of frame k (one sequence, ``block_frames``
            consecutive frames); cross-validation folds are unions of whole blocks.
    """

    d: np.ndarray
    positive: np.ndarray
    block: np.ndarray

    def __len__(self) -> int:
        return len(self.positive)


def collect_pairs(sequences: Iterable, max_frames: int | None = None, min_visibility: float = 0.7,
                  bins: int = 4, neighbours: int = 3, radius: float = 1.0,
                  block_frames: int = 25, motion_compensation: bool = True) -> PairSamples:
    """Positive and negative frame-to-frame pairs of annotated people (PBM 4.1 samples).

    Args:
        sequences: ``harness.datasets.base.Sequence`` objects with ground truth and frames.
        max_frames: frames read per sequence (None = all).
        min_visibility: people below this visibility (when known) or flagged occluded are
            skipped: the models describe unoccluded matches.
        bins: histogram bins per channel (must match the tracker's ``histogram_bins``).
        neighbours: negatives per person and frame: the nearest other people (0 = none).
        radius: a negative's box centre lies within ``radius`` x (w, h) of the person's
            previous centre (w, h its previous box size), like the tracker's gate (PBM 3).
        block_frames: frames per cross-validation block.
        motion_compensation: as the tracker's ``motion_compensation``: the previous frame's
            parts are moved by the person's previous step (its centroid in frame k-1 minus
            in frame k-2; none when it was not kept in frame k-2) before the overlap and
            displacement differences are taken, as the tracker moves a target's parts model
            by KF1's constant-velocity prediction.
    Returns:
        ``PairSamples``; positives are exactly the pairs ``collect_differences`` returns.
    """
    if neighbours < 0 or radius < 0 or block_frames < 1:
        raise ValueError(f"collect_pairs: neighbours ({neighbours}) and radius ({radius}) must "
                         f"be >= 0 and block_frames ({block_frames}) >= 1")
    ex = PartFeatureExtractor(bins)
    ds: list[np.ndarray] = []
    pos: list[np.ndarray] = []
    blocks: list[np.ndarray] = []
    block_base = 0
    for seq in sequences:
        if seq.gt is None:
            log.warning("%s: no ground truth, skipped", seq.info.name)
            continue
        table = seq.gt.table
        occluded = seq.gt.occluded
        prev = None  # (ids, boxes, features, centroids) of the previous frame
        before: dict[int, np.ndarray] = {}  # id -> centroid, the frame before that
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
            boxes = np.asarray(table.boxes[rows], dtype=np.float64)
            ex.start(frame, fg)
            if len(rows) == 0:
                prev, before = None, {}
                continue
            cents = np.array([_centroid(fg, b) for b in boxes])
            al, be = centroid_ratios(boxes, cents)
            feats = ex.extract(boxes, al, be)
            if prev is not None:
                ti, ci, is_pos = _pairs(prev[0], prev[1], ids, boxes, neighbours, radius)
                if len(ti):
                    model = prev[2]
                    if motion_compensation:
                        model = model.shifted(np.array([
                            c - before[i] if i in before else np.zeros(2)
                            for i, c in zip(prev[0].tolist(), prev[3])]).reshape(-1, 2))
                    d = feature_differences(model, feats)[ti, ci]  # (K, 6, 5)
                    ds.append(d)
                    pos.append(is_pos)
                    blocks.append(np.full(len(ti), block_base + (k - 1) // block_frames, np.int64))
                before = dict(zip(prev[0].tolist(), prev[3]))
            prev = (ids, boxes, feats, cents)
        block_base += (n - 1) // block_frames + 1
    if not ds:
        return PairSamples(np.zeros((0, len(FEATURES), N_PARTS)), np.zeros(0, bool),
                           np.zeros(0, np.int64))
    return PairSamples(np.concatenate(ds), np.concatenate(pos), np.concatenate(blocks))


def _pairs(prev_ids: np.ndarray, prev_boxes: np.ndarray, ids: np.ndarray, boxes: np.ndarray,
           neighbours: int, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index pairs (previous person, current person) and whether they are the same person.

    Per previous person: itself when present, then its ``neighbours`` nearest other people
    (centre distance) whose centre lies within ``radius`` x (w, h) of its previous centre.
    Boxes are (N, 4) xywh.
    """
    pc = prev_boxes[:, :2] + prev_boxes[:, 2:] / 2
    cc = boxes[:, :2] + boxes[:, 2:] / 2
    off = np.abs(cc[None] - pc[:, None])  # (P, C, 2)
    near = np.all(off <= radius * prev_boxes[:, None, 2:], axis=2)
    dist = np.hypot(off[..., 0], off[..., 1])
    same = prev_ids[:, None] == ids[None]
    ti: list[int] = []
    ci: list[int] = []
    for t in range(len(prev_ids)):
        hit = np.flatnonzero(same[t])
        ti += [t] * len(hit)
        ci += hit.tolist()
        other = np.flatnonzero(near[t] & ~same[t])
        other = other[np.argsort(dist[t, other], kind="stable")][:neighbours]
        ti += [t] * len(other)
        ci += other.tolist()
    ti_a, ci_a = np.array(ti, np.intp), np.array(ci, np.intp)
    return ti_a, ci_a, same[ti_a, ci_a]


def collect_differences(sequences: Iterable, max_frames: int | None = None,
                        min_visibility: float = 0.7, bins: int = 4,
                        motion_compensation: bool = True) -> dict[str, np.ndarray]:
    """Frame-to-frame part feature differences of annotated people (eq. 11).

    Args:
        sequences: ``harness.datasets.base.Sequence`` objects with ground truth and frames.
        max_frames: frames read per sequence (None = all).
        min_visibility: people below this visibility (when known) or flagged occluded are
            skipped: the models describe unoccluded matches.
        bins: histogram bins per channel (must match the tracker's ``histogram_bins``).
        motion_compensation: see ``collect_pairs``.
    Returns:
        {feature: (K, 5) differences}.
    """
    return positive_differences(collect_pairs(sequences, max_frames, min_visibility, bins,
                                              neighbours=0,
                                              motion_compensation=motion_compensation))


def positive_differences(samples: PairSamples) -> dict[str, np.ndarray]:
    """{feature: (K, 5) differences} of the positive pairs (what the models are fitted on)."""
    d = samples.d[samples.positive]
    return {f: d[:, i] for i, f in enumerate(FEATURES)}


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


# ---------------------------------------------------------------------------------------
# feature weights omega (PBM 4.1, eq. 12)


@dataclass
class WeightFit:
    """The learned omega of eq. 12 and how it was chosen (PBM 4.1).

    Attributes:
        weights: {feature: omega_i}, sum 1.
        accuracy: mean validation accuracy of ``weights`` over the folds.
        fold_accuracy: (k,) validation accuracy of ``weights`` per fold.
        nested_accuracy: mean over folds of the validation accuracy of the omega chosen on
            the other folds alone (an unbiased estimate of the whole procedure).
        reference_accuracy: mean validation accuracy of ``reference`` weights, if given.
        settings: grid step, grid points, folds, threshold, spread, gamma, sample counts.
    """

    weights: dict[str, float]
    accuracy: float
    fold_accuracy: np.ndarray
    nested_accuracy: float
    reference_accuracy: float | None = None
    settings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {
            "accuracy": round(float(self.accuracy), 6),
            "fold_accuracy": [round(float(v), 6) for v in self.fold_accuracy],
            "nested_accuracy": round(float(self.nested_accuracy), 6),
        }
        if self.reference_accuracy is not None:
            out["reference_accuracy"] = round(float(self.reference_accuracy), 6)
        out.update(self.settings)
        return out


def weight_grid(step: float) -> np.ndarray:
    """omega on the grid {0, step, ..., 1}^6, normalised to sum 1 (PBM 4.1).

    The all-zero point is skipped and points equal after normalising are kept once.
    Returns:
        (G, 6) float64 weights, rows in lexicographic order of their reduced integer form.
    """
    n = round(1.0 / step)
    if n < 1 or abs(n * step - 1.0) > 1e-9:
        raise ValueError(f"weight step must divide 1 (e.g. 0.1, 0.2, 0.25), got {step}")
    axes = np.meshgrid(*[np.arange(n + 1)] * len(FEATURES), indexing="ij")
    v = np.stack([a.reshape(-1) for a in axes], axis=1)[1:]  # skip all zero
    g = np.gcd.reduce(v, axis=1)
    v = np.unique(v // g[:, None], axis=0)
    return v / v.sum(axis=1, keepdims=True)


def feature_scores(models: FeatureModels, d: np.ndarray, gamma: np.ndarray, spread: float
                   ) -> np.ndarray:
    """q_i = sum_j gamma_j p(d_ij / spread | theta_ij), so that eq. 13 of eq. 12 is q @ omega.

    Args:
        d: (M, 6, 5) differences; gamma: (5,) part weights (normalised here).
    Returns:
        (M, 6) float64.
    """
    gamma = np.asarray(gamma, dtype=np.float64)
    gamma = gamma / gamma.sum()
    prob = models.match_probability(np.asarray(d, dtype=np.float64) / spread)  # (M, 6, 5)
    return prob @ gamma


def block_folds(block: np.ndarray, k: int) -> np.ndarray:
    """Fold of every sample: whole blocks, round-robin over the sorted block ids.

    Args:
        block: (M,) block ids. k: folds.
    Returns:
        (M,) int fold in [0, k).
    """
    ids, inv = np.unique(np.asarray(block), return_inverse=True)
    if len(ids) < k:
        raise ValueError(f"{k}-fold cross-validation needs >= {k} blocks, got {len(ids)}")
    return (np.arange(len(ids)) % k)[inv.reshape(-1)]


def fold_accuracies(q: np.ndarray, positive: np.ndarray, folds: np.ndarray, k: int,
                    grid: np.ndarray, threshold: float, chunk: int = 1024) -> np.ndarray:
    """Balanced accuracy of the match decision p >= threshold per grid point and fold.

    Args:
        q: (M, 6) ``feature_scores``; positive: (M,) bool; folds: (M,) fold ids.
        grid: (G, 6) omega (rows sum to 1); the global score is q @ omega (eqs. 12-13).
    Returns:
        (G, k) accuracy: within a fold, positives and negatives weigh half each (all of it
        when the fold holds one class only).
    """
    positive = np.asarray(positive, dtype=bool)
    wt = np.zeros((len(q), k))
    for f in range(k):
        classes = [positive & (folds == f), ~positive & (folds == f)]
        present = [c for c in classes if c.any()]
        for c in present:
            wt[c, f] = 1.0 / (len(present) * c.sum())
    out = np.empty((len(grid), k))
    for s in range(0, len(grid), chunk):
        p = grid[s:s + chunk] @ q.T  # (c, M) global scores, eq. 13
        correct = (p >= threshold) == positive[None]
        out[s:s + chunk] = correct.astype(np.float64) @ wt
    return out


def pick_best(mean_accuracy: np.ndarray, grid: np.ndarray, tol: float = 1e-12) -> int:
    """Index of the best accuracy; ties: nearest the uniform weights, then first in order."""
    best = np.flatnonzero(mean_accuracy >= mean_accuracy.max() - tol)
    dist = np.linalg.norm(grid[best] - 1.0 / grid.shape[1], axis=1)
    return int(best[np.argmin(dist)])


def search_weights(samples: PairSamples, models: FeatureModels, gamma: np.ndarray,
                   threshold: float, spread: float, step: float = 0.2, k: int = 5,
                   reference: Mapping[str, float] | None = None) -> WeightFit:
    """omega of eq. 12 with the best k-fold cross-validation accuracy (PBM 4.1).

    Args:
        samples: positive and negative pairs (``collect_pairs``).
        models: the fitted difference models theta_ij.
        gamma: (5,) part weights of eq. 13; threshold: the tracker's ``match_threshold``;
            spread: its ``model_spread``.
        step: grid step over [0, 1] per feature. k: folds (whole blocks).
        reference: weights whose accuracy is reported beside (e.g. the hand-set ones).
    Raises:
        ValueError when the samples hold no positive or no negative pair or too few blocks.
    """
    n_pos = int(samples.positive.sum())
    n_neg = len(samples) - n_pos
    if n_pos == 0 or n_neg == 0:
        raise ValueError(f"weight search needs positive and negative pairs, got {n_pos} and {n_neg}")
    grid = weight_grid(step)
    folds = block_folds(samples.block, k)
    log.info("searching omega: %d grid points, %d positive and %d negative pairs, %d folds",
             len(grid), n_pos, n_neg, k)
    q = feature_scores(models, samples.d, gamma, spread)
    acc = fold_accuracies(q, samples.positive, folds, k, grid, threshold)
    mean = acc.mean(axis=1)
    best = pick_best(mean, grid)
    nested = []
    for f in range(k):
        train = np.delete(acc, f, axis=1).mean(axis=1)
        nested.append(acc[pick_best(train, grid), f])
    ref_acc = None
    if reference is not None:
        w = np.array([float(reference[f]) for f in FEATURES])
        ref_acc = float(fold_accuracies(q, samples.positive, folds, k, w[None] / w.sum(),
                                        threshold).mean())
    settings = {
        "grid_step": float(step),
        "grid_points": len(grid),
        "folds": int(k),
        "blocks": len(np.unique(samples.block)),
        "positives": n_pos,
        "negatives": n_neg,
        "match_threshold": float(threshold),
        "model_spread": float(spread),
        "part_weights": [float(g) for g in np.asarray(gamma, dtype=np.float64)],
    }
    weights = {f: round(float(v), 6) for f, v in zip(FEATURES, grid[best], strict=True)}
    log.info("omega %s: mean cross-validation accuracy %.4f (nested %.4f) over %d grid points",
             weights, mean[best], np.mean(nested), len(grid))
    return WeightFit(weights, float(mean[best]), acc[best].copy(), float(np.mean(nested)),
                     ref_acc, settings)


# ---------------------------------------------------------------------------------------
# YAML


def save_fit(models: FeatureModels, path: str | Path, header: str = "",
             weights: WeightFit | None = None) -> None:
    """Write the models as YAML (``load_feature_models`` reads them) with a ``#`` header and,
    when given, top-level ``feature_weights`` and ``feature_weights_fit`` first."""
    body = ""
    if weights is not None:
        body = yaml.safe_dump({"feature_weights": dict(weights.weights)}, sort_keys=False,
                              default_flow_style=False)
        body += yaml.safe_dump({"feature_weights_fit": weights.to_dict()}, sort_keys=False,
                               default_flow_style=None)
    body += yaml.safe_dump(models.to_dict(), sort_keys=False, default_flow_style=None)
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    Path(path).write_text("\n".join(lines) + ("\n" if lines else "") + body)


def load_feature_weights(path: str | Path) -> dict[str, float] | None:
    """The ``feature_weights`` (omega, eq. 12) of a file written by ``save_fit``; None for
    files without them (older fits).

    Raises:
        ValueError naming the file and key when the entry is malformed.
    """
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read {p}: {exc}") from exc
    if not isinstance(data, dict) or data.get("feature_weights") is None:
        return None
    fw = data["feature_weights"]
    if not isinstance(fw, dict) or sorted(fw) != sorted(FEATURES):
        raise ValueError(f"{p}: feature_weights must map exactly {list(FEATURES)}, got {fw!r}")
    try:
        return {f: float(fw[f]) for f in FEATURES}
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{p}: feature_weights: {exc}") from exc


def weights_override(weights: Mapping[str, float], prefix: str = "tracker.pbm") -> str:
    """The Hydra command-line override that sets omega, e.g. for ``python -m harness``."""
    body = ",".join(f"{f}:{float(weights[f]):g}" for f in FEATURES)
    return f"'{prefix}.features.feature_weights={{{body}}}'"


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


def _tracker_settings(path: str | Path) -> dict:
    """features.part_weights, matching.match_threshold, adaptations.model_spread and
    features.feature_weights of a tracker config (as ``part_weights``, ...), and its
    adaptations.motion_compensation (the tracker's default, true, when the key is absent)."""
    p = Path(path)
    try:
        cfg = yaml.safe_load(p.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read tracker config {p}: {exc}") from exc
    out = {}
    for group, key in (("features", "part_weights"), ("matching", "match_threshold"),
                       ("adaptations", "model_spread"), ("features", "feature_weights")):
        node = cfg.get(group) if isinstance(cfg, dict) else None
        if not isinstance(node, dict) or key not in node:
            raise ValueError(f"{p}: key {group}.{key!r} missing")
        out[key] = node[key]
    out["motion_compensation"] = bool(cfg["adaptations"].get("motion_compensation", True))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="occbench fit pbm", description=__doc__.split("\n")[0])
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
    ap.add_argument("--no-weights", action="store_true", help="fit the models only, no omega")
    ap.add_argument("--weight-step", type=float, default=0.2, help="omega grid step over [0, 1]")
    ap.add_argument("--folds", type=int, default=5, help="cross-validation folds")
    ap.add_argument("--block-frames", type=int, default=25, help="frames per fold block")
    ap.add_argument("--neighbours", type=int, default=3, help="negatives per person and frame")
    ap.add_argument("--radius", type=float, default=1.0,
                    help="negatives' centres within radius x (w, h) of the person's centre")
    ap.add_argument("--tracker-config", default=str(TRACKER_CONFIG),
                    help="tracker YAML giving features.part_weights, matching.match_threshold, "
                         "adaptations.model_spread and adaptations.motion_compensation")
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
    tracker = _tracker_settings(args.tracker_config)
    samples = collect_pairs(sequences, args.max_frames, args.min_visibility, args.bins,
                            neighbours=0 if args.no_weights else args.neighbours,
                            radius=args.radius, block_frames=args.block_frames,
                            motion_compensation=tracker["motion_compensation"])
    diffs = positive_differences(samples)
    description = "fitted on " + "; ".join(sources)
    if tracker["motion_compensation"]:
        description += "; overlap and displacement motion-compensated"
    models = fit_models(diffs, description)
    fit = None
    if not args.no_weights:
        try:
            fit = search_weights(samples, models, np.asarray(tracker["part_weights"], float),
                                 float(tracker["match_threshold"]), float(tracker["model_spread"]),
                                 args.weight_step, args.folds, tracker["feature_weights"])
        except ValueError as exc:
            log.warning("feature weights not learned: %s", exc)
        else:
            fit.settings.update(neighbours=args.neighbours, radius=args.radius,
                                block_frames=args.block_frames)
    header = (f"PBM feature-difference models (PBM 2.2), written by `python -m harness.fit pbm`.\n"
              f"{description}; {len(diffs['area'])} frame-to-frame differences per part;\n"
              f"histogram_bins {args.bins}, min visibility {args.min_visibility}.\n"
              "Each entry: a folded Gaussian mixture over |difference| (half_normal = one "
              "component with mean 0).")
    if fit is not None:
        header += ("\nfeature_weights: omega of eq. 12 with the best cross-validation accuracy "
                   "(PBM 4.1); use with\n"
                   f"  tracker.pbm.features.models.path={args.out} {weights_override(fit.weights)}")
    save_fit(models, args.out, header, fit)
    log.info("wrote %s (%d differences per part)", args.out, len(diffs["area"]))
    for f in FEATURES:
        log.info("%-12s %s", f, " ".join(f"{m.kind[:4]}:{m.sigmas.max():.3f}" for m in models.models[f]))
    if fit is not None:
        print("feature_weights (omega, PBM eq. 12): "
              + ", ".join(f"{f} {w:.3f}" for f, w in fit.weights.items()))
        ref = "" if fit.reference_accuracy is None else f"; hand-set weights {fit.reference_accuracy:.4f}"
        print(f"{args.folds}-fold cross-validation accuracy {fit.accuracy:.4f} "
              f"(nested {fit.nested_accuracy:.4f}{ref}) on {fit.settings['positives']} positive and "
              f"{fit.settings['negatives']} negative pairs, {fit.settings['grid_points']} grid points")
        print(f"use with: python -m harness tracker.pbm.features.models.path={args.out} "
              f"{weights_override(fit.weights)}")
    if args.plot:
        plot_models(models, diffs, args.plot)
        log.info("wrote %s", args.plot)
    return 0
