"""``occbench fit pbm``: fit the PBM feature-difference models (PBM 2.2, Fig. 3)
and learn the feature weights omega of eq. 12 (PBM 4.1).

Models. For every annotated person visible in two consecutive frames, the five parts of
its ground-truth box are measured in both frames (``occbench.trackers.layered.parts``) and the
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
over a grid of [0, 1]^6 with step ``--weight-step`` (normalised to sum 1, all-zero skipped,
duplicates after normalising merged); the accuracy (balanced: positives and negatives weigh half each) is
cross-validated over ``--folds`` folds of whole frame blocks (``--block-frames`` frames of
one sequence), so neighbouring frames do not leak between training and validation. The
omega with the best mean validation accuracy wins; ties go to the one nearest the uniform
weights, then to the first in grid order. gamma, threshold and spread are read from
``--tracker-config`` (a file, or the name of a ``conf/tracker`` config composed by Hydra,
e.g. ``pbm_paper``; default ``conf/tracker/pbm.yaml``).

The YAML (for ``conf/tracker/pbm.yaml``'s ``features.models.path``) holds the models and, as
extra top-level keys that the model loader ignores, ``feature_weights`` and
``feature_weights_fit`` (accuracies, grid, folds, sample counts). A PNG shows the fitted
densities over the histograms of the differences (the paper's Fig. 3).

Sources (any combination; a real source may name a frame window, ``ROOT@FIRST-LAST``,
1-based inclusive, original frame numbers):
    --synthetic [NAME ...]   built-in synthetic scenarios (occbench.datasets.synthetic)
    --mot ROOT[@F-L] ...     MOTChallenge folder(s) with frames and gt (occbench.datasets.mot)
    --caviar ROOT[@F-L] ...  CAVIAR sequence folder(s): video or JPEGs and CVML gt with its
                             occlusion labels (occbench.datasets.caviar)

The foreground (``--foreground``) is what the tracker would get: ``auto`` = the sequence's
exact label image when it has one (synthetic scenes), else the whole box (with a warning:
area and perimeter then carry no information); ``mog2`` = the front end's background
subtraction (``occbench.trackers.frontend.BackgroundModel`` at its defaults, which are
``detector=foreground``'s), for real frames.

Real frames (``tracker=pbm_paper``'s models, ``trackers/layered/data/real_uncompensated.yaml``;
the fitting split of docs/generalisation.md; ``DATA``: the folder of the not-shipped data)::

    occbench fit pbm --caviar datasets/CAVIAR-OneLeaveShop1cor@1-150 \
        --mot DATA/CAVIAR-EnterExitCrossingPaths1cor@1-180 \
        --foreground mog2 --tracker-config pbm_paper \
        --out trackers/layered/data/real_uncompensated.yaml \
        --plot docs/img/pbm_models_real_vs_synthetic.png \
        --compare trackers/layered/data/default_models.yaml \
        --compare-label "synthetic, compensated (default_models.yaml)"

(The omega it also learns, written in the file, is not used: pbm_paper keeps pbm.yaml's.)
Example:
    occbench fit pbm --synthetic --seed 1 --out models.yaml --plot models.png

Using the learned weights (the command prints the exact line):
    python -m occbench tracker.pbm.features.models.path=models.yaml \\
        'tracker.pbm.features.feature_weights={area:0.2,perimeter:0.0,hsv:0.2,xyz:0.4,displacement:0.2,overlap:0.0}'
(``tracker.features.feature_weights=...`` when the run selects ``tracker=pbm`` alone.)
Measured on held-out data, the omega learned on synthetic seed 1 tracks worse than the
hand-set default although it classifies held-out pairs better: see
``benchmarks/bench_pbm_weights.py``.
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Mapping
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import yaml
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from occbench.config import register
from occbench.datasets.base import window
from occbench.datasets.caviar import load_caviar
from occbench.datasets.mot import load_mot
from occbench.datasets.synthetic import DEFAULT_SCENARIOS, load_suite
from occbench.fit.pbm_pairs import collect_pairs, positive_differences
from occbench.fit.pbm_weights import WeightFit, search_weights
from occbench.progress import log_to_stderr
from occbench.trackers.layered.feature_models import (
    FeatureModels,
    FoldedMixture,
    fit_difference_model,
    load_feature_models,
)
from occbench.trackers.layered.parts import FEATURES, N_PARTS, PART_NAMES

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
TRACKER_CONFIG = ROOT / "conf" / "tracker" / "pbm.yaml"

MIN_SIGMA = {"area": 0.01, "perimeter": 0.01, "hsv": 0.01, "xyz": 0.01, "displacement": 0.003,
             "overlap": 0.01}
"""Smallest standard deviation per feature: exact synthetic data would otherwise give
degenerate, over-confident models."""


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
    """The Hydra command-line override that sets omega, e.g. for ``python -m occbench``."""
    body = ",".join(f"{f}:{float(weights[f]):g}" for f in FEATURES)
    return f"'{prefix}.features.feature_weights={{{body}}}'"


def spread(model: FoldedMixture) -> float:
    """Root mean square of a fitted difference model, sqrt(E[d^2]) = sqrt(sum_k w_k (mu_k^2 +
    sigma_k^2)) (a folded component has the same second moment as its Gaussian): one number
    for how large a true match's difference is expected to be."""
    return float(np.sqrt(np.sum(model.weights * (model.means ** 2 + model.sigmas ** 2))))


def plot_models(models: FeatureModels, diffs: dict[str, np.ndarray], path: str | Path,
                reference: FeatureModels | None = None,
                labels: tuple[str, str] = ("fitted", "reference")) -> None:
    """Histograms of the differences with the fitted densities (Fig. 3), 6 x 5 panels; with
    ``reference``, its densities dashed beside them, a legend and each model's spread
    (``spread``) in the panel titles."""
    matplotlib.use("Agg")

    fig, axes = plt.subplots(len(FEATURES), N_PARTS, figsize=(3.0 * N_PARTS, 2.2 * len(FEATURES)))
    for i, f in enumerate(FEATURES):
        for j, part in enumerate(PART_NAMES):
            ax = axes[i, j]
            d = diffs[f][:, j]
            m = models.models[f][j]
            hi = max(float(np.quantile(d, 0.995)) if len(d) else 1.0, 4 * float(m.sigmas.max()) * 0.5, 1e-3)
            ax.hist(d, bins=40, range=(0, hi), density=True, color="0.75")
            x = np.linspace(0, hi, 200)
            ax.plot(x, m.pdf(x), color="C3", lw=1.5, label=labels[0])
            title = f"{f} / {part} ({m.kind}, n={len(d)})"
            if reference is not None:
                r = reference.models[f][j]
                ax.plot(x, r.pdf(x), color="C0", lw=1.2, ls="--", label=labels[1])
                title = f"{f} / {part}: rms {spread(m):.3f} vs {spread(r):.3f}"
            ax.set_title(title, fontsize=7)
            ax.tick_params(labelsize=6)
    bottom = 0.0
    if reference is not None:
        handles, names = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles + [plt.Rectangle((0, 0), 1, 1, color="0.75")],
                   names + ["histogram of the fitted differences"], loc="lower center", ncol=3,
                   fontsize=9)
        bottom = 0.03
    fig.suptitle("PBM feature differences between consecutive frames and fitted densities")
    fig.tight_layout(rect=(0, bottom, 1, 0.98))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _tracker_settings(path: str | Path) -> dict:
    """features.part_weights, matching.match_threshold, adaptations.model_spread and
    features.feature_weights of a tracker config (as ``part_weights``, ...), and its
    adaptations.motion_compensation (the tracker's default, true, when the key is absent).
    ``path``: a YAML file, or the name of a ``conf/tracker`` config (its defaults list
    composed by Hydra)."""
    p = Path(path)
    if p.suffix == "" and (ROOT / "conf" / "tracker" / f"{p}.yaml").is_file():
        cfg, p = _composed_tracker(str(path)), ROOT / "conf" / "tracker" / f"{p}.yaml"
    else:
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


def _composed_tracker(name: str) -> dict:
    """``conf/tracker/<name>.yaml`` composed by Hydra (its defaults list applied), as a dict."""
    register()  # the project's resolvers and launcher
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base=None):
        cfg = compose(config_name="config", overrides=[f"tracker={name}"])
    return OmegaConf.to_container(cfg.tracker, resolve=True)


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="occbench fit pbm", description=__doc__.split("\n")[0])
    ap.add_argument("--synthetic", nargs="*", metavar="NAME", default=None,
                    help="synthetic scenarios (no names = the default suite)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the synthetic scenes")
    ap.add_argument("--length", type=int, default=150, help="frames per synthetic scene")
    ap.add_argument("--mot", nargs="*", default=[], metavar="ROOT[@F-L]",
                    help="MOTChallenge folders, optionally with a frame window")
    ap.add_argument("--caviar", nargs="*", default=[], metavar="ROOT[@F-L]",
                    help="CAVIAR sequence folders, optionally with a frame window")
    ap.add_argument("--foreground", choices=("auto", "mog2", "none"), default="auto",
                    help="foreground the parts are measured on (mog2 for real frames)")
    ap.add_argument("--max-frames", type=int, default=None, help="frames read per sequence")
    ap.add_argument("--min-visibility", type=float, default=0.7)
    ap.add_argument("--bins", type=int, default=4, help="histogram bins per channel")
    ap.add_argument("--out", required=True, help="output YAML")
    ap.add_argument("--plot", default=None, help="output PNG of the fitted densities (Fig. 3)")
    ap.add_argument("--compare", default=None, metavar="MODELS",
                    help="models YAML drawn beside the fitted ones in --plot (and rms spreads logged)")
    ap.add_argument("--compare-label", default=None, help="legend label of --compare")
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
    return ap


def _sequences(args: argparse.Namespace) -> tuple[list, list[str]]:
    """The sequences of ``--synthetic`` and ``--mot``, and a description of each source."""
    sequences = []
    sources = []
    if args.synthetic is not None:
        names = args.synthetic or list(DEFAULT_SCENARIOS)
        sequences += load_suite(names, seed=args.seed, length=args.length)
        sources.append(f"synthetic scenarios {', '.join(names)} (seed {args.seed}, {args.length} frames)")
    for kind, roots, load in (("MOT", args.mot, load_mot), ("CAVIAR", args.caviar, load_caviar)):
        for spec in roots:
            root, frames = _window_spec(spec)
            try:
                sequences += window(load(root), frames)
            except (OSError, ValueError) as exc:
                raise SystemExit(f"occbench fit pbm: {kind} source {spec}: {exc}") from exc
            where = "" if frames is None else f" frames {frames[0]}-{frames[1]}"
            sources.append(f"{kind} {Path(root).name}{where}")
    return sequences, sources


def _window_spec(spec: str) -> tuple[str, list[int] | None]:
    """``ROOT`` or ``ROOT@FIRST-LAST`` -> (root, [first, last] or None).

    Raises:
        SystemExit naming the argument when the window is not two integers.
    """
    root, at, frames = spec.rpartition("@")
    if not at:
        return spec, None
    try:
        first, last = (int(v) for v in frames.split("-"))
    except ValueError:
        raise SystemExit(f"occbench fit pbm: {spec!r}: a frame window is ROOT@FIRST-LAST") from None
    return root, [first, last]


def _header(args: argparse.Namespace, description: str, n: int, fit: WeightFit | None) -> str:
    """The ``#`` header of the written YAML."""
    header = (f"PBM feature-difference models (PBM 2.2), written by `occbench fit pbm`.\n"
              f"{description}; {n} frame-to-frame differences per part;\n"
              f"histogram_bins {args.bins}, min visibility {args.min_visibility}.\n"
              "Each entry: a folded Gaussian mixture over |difference| (half_normal = one "
              "component with mean 0).")
    if fit is not None:
        header += ("\nfeature_weights: omega of eq. 12 with the best cross-validation accuracy "
                   "(PBM 4.1); use with\n"
                   f"  tracker.pbm.features.models.path={args.out} {weights_override(fit.weights)}")
    return header


def _print_fit(args: argparse.Namespace, fit: WeightFit) -> None:
    """The learned omega, its accuracies and the override that uses it, on stdout."""
    print("feature_weights (omega, PBM eq. 12): "
          + ", ".join(f"{f} {w:.3f}" for f, w in fit.weights.items()))
    ref = "" if fit.reference_accuracy is None else f"; hand-set weights {fit.reference_accuracy:.4f}"
    print(f"{args.folds}-fold cross-validation accuracy {fit.accuracy:.4f} "
          f"(nested {fit.nested_accuracy:.4f}{ref}) on {fit.settings['positives']} positive and "
          f"{fit.settings['negatives']} negative pairs, {fit.settings['grid_points']} grid points")
    print(f"use with: python -m occbench tracker.pbm.features.models.path={args.out} "
          f"{weights_override(fit.weights)}")


def main(argv: list[str] | None = None) -> int:
    ap = _parser()
    args = ap.parse_args(argv)
    log_to_stderr()
    sequences, sources = _sequences(args)
    if not sequences:
        ap.error("give --synthetic, --mot and/or --caviar")
    tracker = _tracker_settings(args.tracker_config)
    samples = collect_pairs(sequences, args.max_frames, args.min_visibility, args.bins,
                            neighbours=0 if args.no_weights else args.neighbours,
                            radius=args.radius, block_frames=args.block_frames,
                            motion_compensation=tracker["motion_compensation"],
                            foreground=args.foreground)
    diffs = positive_differences(samples)
    description = "fitted on " + "; ".join(sources)
    description += ("; overlap and displacement motion-compensated" if tracker["motion_compensation"]
                    else "; uncompensated (eq. 11 against the last frame)")
    if args.foreground != "auto":
        description += f"; foreground {args.foreground}"
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
    header = _header(args, description, len(diffs["area"]), fit)
    save_fit(models, args.out, header, fit)
    log.info("wrote %s (%d differences per part)", args.out, len(diffs["area"]))
    for f in FEATURES:
        log.info("%-12s %s", f, " ".join(f"{m.kind[:4]}:{m.sigmas.max():.3f}" for m in models.models[f]))
    if fit is not None:
        _print_fit(args, fit)
    reference = None if args.compare is None else load_feature_models(args.compare)
    if args.plot:
        plot_models(models, diffs, args.plot, reference,
                    (f"fitted ({Path(args.out).name})", args.compare_label or str(args.compare)))
        log.info("wrote %s", args.plot)
    if reference is not None:
        for f in FEATURES:
            log.info("rms %-12s %s", f, " ".join(
                f"{spread(m):.3f}/{spread(r):.3f}"
                for m, r in zip(models.models[f], reference.models[f], strict=True)))
    return 0
