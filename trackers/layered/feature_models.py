"""Feature-difference models p(d | theta) of the PBM tracker (PBM 2.2, eqs. 11-12).

For every feature i and part j the absolute frame-to-frame difference d_ij = |f_ij - F_ij|
(eq. 11) of correctly matched targets is modelled by a half-normal density or, where the
differences are not unimodal, by a mixture of folded normals (a Gaussian mixture on the
signed difference, folded at 0). Both are one class, ``FoldedMixture``: a half-normal is
one component with mean 0.

The tracker turns a difference into a match probability with the model's survival
function P(D >= d): the probability that a true match shows a difference at least this
large. It lies in [0, 1], is 1 at d = 0 and decreases with d, so eq. 12's weighted sum of
such probabilities is itself in [0, 1] and one threshold serves every feature. (The paper
writes p(d | theta); a raw density is not comparable across features with different
scales, which the weighted sum of eq. 12 requires.)

Models are stored as YAML (``save_feature_models`` / ``load_feature_models``); the
shipped defaults are ``trackers/layered/data/default_models.yaml``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from occbench.trackers.layered.parts import FEATURES, N_PARTS, PART_NAMES
from occbench.trackers.layered.scores import survival_kernel
from scipy.special import ndtr

logger = logging.getLogger(__name__)


DEFAULT_MODELS_PATH = Path(__file__).with_name("data") / "default_models.yaml"


@dataclass
class FoldedMixture:
    """Mixture of folded normals over d >= 0; a half-normal is ``means == [0]``.

    Attributes:
        weights, means, sigmas: (K,) float64, weights sum to 1, sigmas > 0.
    """

    weights: np.ndarray
    means: np.ndarray
    sigmas: np.ndarray

    def __post_init__(self) -> None:
        self.weights = np.asarray(self.weights, dtype=np.float64).reshape(-1)
        self.means = np.asarray(self.means, dtype=np.float64).reshape(-1)
        self.sigmas = np.asarray(self.sigmas, dtype=np.float64).reshape(-1)
        k = len(self.weights)
        if k == 0 or len(self.means) != k or len(self.sigmas) != k:
            raise ValueError("FoldedMixture: weights, means and sigmas need one equal length >= 1")
        if (self.sigmas <= 0).any() or not np.isfinite(self.sigmas).all():
            raise ValueError(f"FoldedMixture: sigmas must be positive, got {self.sigmas}")
        if (self.weights < 0).any() or not np.isclose(self.weights.sum(), 1.0, atol=1e-6):
            raise ValueError(f"FoldedMixture: weights must be >= 0 and sum to 1, got {self.weights}")

    @property
    def kind(self) -> str:
        return "half_normal" if len(self.weights) == 1 and self.means[0] == 0 else "mixture"

    def pdf(self, d: np.ndarray) -> np.ndarray:
        """Density of the folded mixture at d >= 0 (0 for d < 0)."""
        d = np.asarray(d, dtype=np.float64)[..., None]
        z1 = (d - self.means) / self.sigmas
        z2 = (d + self.means) / self.sigmas
        c = self.weights / (self.sigmas * np.sqrt(2 * np.pi))
        out = (c * (np.exp(-0.5 * z1**2) + np.exp(-0.5 * z2**2))).sum(-1)
        return np.where(d[..., 0] >= 0, out, 0.0)

    def survival(self, d: np.ndarray) -> np.ndarray:
        """P(D >= d): the match probability of a difference d (1 at d <= 0)."""
        d = np.maximum(np.asarray(d, dtype=np.float64), 0.0)[..., None]
        s = ndtr((self.means - d) / self.sigmas) + ndtr((-self.means - d) / self.sigmas)
        return np.clip((self.weights * s).sum(-1), 0.0, 1.0)

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "weights": [round(float(v), 6) for v in self.weights],
            "means": [round(float(v), 6) for v in self.means],
            "sigmas": [round(float(v), 6) for v in self.sigmas],
        }


def fit_half_normal(d: np.ndarray, min_sigma: float = 1e-3) -> FoldedMixture:
    """Maximum-likelihood half-normal: sigma^2 = mean(d^2), floored at ``min_sigma``."""
    d = np.abs(np.asarray(d, dtype=np.float64).reshape(-1))
    sigma = float(np.sqrt(np.mean(d**2))) if len(d) else 1.0
    return FoldedMixture([1.0], [0.0], [max(sigma, min_sigma)])


def fit_folded_mixture(
    d: np.ndarray, components: int = 2, iterations: int = 200, min_sigma: float = 1e-3
) -> FoldedMixture:
    """EM for a mixture of folded normals (the sign of each d is a second latent variable).

    Deterministic: components start at evenly spaced quantiles of d.
    """
    d = np.abs(np.asarray(d, dtype=np.float64).reshape(-1))
    k = components
    if len(d) < 2 * k:
        return fit_half_normal(d, min_sigma)
    mu = np.quantile(d, (np.arange(k) + 0.5) / k)
    sigma = np.full(k, max(float(d.std()) / k, min_sigma))
    pi = np.full(k, 1.0 / k)
    x = np.stack([d, -d], axis=1)[:, :, None]  # (n, 2 signs, 1)
    prev = -np.inf
    for _ in range(iterations):
        logp = (np.log(pi) - np.log(sigma) - 0.5 * ((x - mu) / sigma) ** 2)  # (n, 2, k)
        m = logp.max(axis=(1, 2), keepdims=True)
        r = np.exp(logp - m)
        tot = r.sum(axis=(1, 2), keepdims=True)
        ll = float((np.log(tot) + m).sum())
        r /= tot
        nk = r.sum(axis=(0, 1)) + 1e-12
        pi = nk / nk.sum()
        mu = (r * x).sum(axis=(0, 1)) / nk
        sigma = np.sqrt((r * (x - mu) ** 2).sum(axis=(0, 1)) / nk)
        sigma = np.maximum(sigma, min_sigma)
        if ll - prev < 1e-8 * abs(ll):
            break
        prev = ll
    mu = np.abs(mu)  # a folded component is the same for +mu and -mu
    order = np.argsort(mu)
    return FoldedMixture(pi[order] / pi.sum(), mu[order], sigma[order])


def log_likelihood(model: FoldedMixture, d: np.ndarray) -> float:
    return float(np.log(np.maximum(model.pdf(np.abs(d)), 1e-300)).sum())


def fit_difference_model(
    d: np.ndarray, min_sigma: float = 1e-3, bic_margin: float = 10.0
) -> FoldedMixture:
    """Half-normal unless a 2-component folded mixture wins by BIC (PBM 2.2).

    BIC = k ln n - 2 ln L with k = 1 (half-normal) or 5 (mixture); the mixture is chosen
    when its BIC is lower by more than ``bic_margin`` (the differences are not unimodal).
    """
    d = np.abs(np.asarray(d, dtype=np.float64).reshape(-1))
    d = d[np.isfinite(d)]
    half = fit_half_normal(d, min_sigma)
    if len(d) < 20:
        return half
    mix = fit_folded_mixture(d, 2, min_sigma=min_sigma)
    n = len(d)
    bic_half = 1 * np.log(n) - 2 * log_likelihood(half, d)
    bic_mix = 5 * np.log(n) - 2 * log_likelihood(mix, d)
    return mix if bic_mix + bic_margin < bic_half else half


class FeatureModels:
    """The 6 x 5 difference models theta_ij (feature i, part j) of eq. 12.

    Args:
        models: {feature: [FoldedMixture] * 5} for every name in ``FEATURES``.
        description: free text (what the models were fitted on).
    """

    def __init__(self, models: dict[str, list[FoldedMixture]], description: str = "") -> None:
        missing = [f for f in FEATURES if f not in models]
        if missing:
            raise ValueError(f"FeatureModels: missing features {missing}")
        for f in FEATURES:
            if len(models[f]) != N_PARTS:
                raise ValueError(f"FeatureModels: feature {f!r} needs {N_PARTS} part models")
        self.models = {f: list(models[f]) for f in FEATURES}
        self.description = description
        k = max(len(m.weights) for f in FEATURES for m in self.models[f])
        # padded (6, 5, K) arrays for the vectorised survival function
        self._w = np.zeros((len(FEATURES), N_PARTS, k))
        self._mu = np.zeros((len(FEATURES), N_PARTS, k))
        self._s = np.ones((len(FEATURES), N_PARTS, k))
        for i, f in enumerate(FEATURES):
            for j, m in enumerate(self.models[f]):
                n = len(m.weights)
                self._w[i, j, :n], self._mu[i, j, :n], self._s[i, j, :n] = m.weights, m.means, m.sigmas

    def match_probability(self, d: np.ndarray) -> np.ndarray:
        """Survival probabilities of differences.

        Args:
            d: (..., 6, 5) differences d_ij (feature i in ``FEATURES`` order, part j).
        Returns:
            (..., 6, 5) probabilities in [0, 1].
        """
        d = np.asarray(d, dtype=np.float64)
        if d.shape[-2:] != self._w.shape[:2]:
            raise ValueError(f"match_probability: expected (..., {len(FEATURES)}, {N_PARTS}) "
                             f"differences, got {d.shape}")
        # the compiled kernel lives with the layers it is fused into (association.py)
        flat = np.ascontiguousarray(d).reshape(-1, *self._w.shape[:2])
        out = np.empty_like(flat)
        survival_kernel(flat, (self._w, self._mu, self._s), out)
        return out.reshape(d.shape)

    def to_dict(self) -> dict:
        return {
            "description": self.description,
            "features": list(FEATURES),
            "parts": list(PART_NAMES),
            "models": {f: {PART_NAMES[j]: m.to_dict() for j, m in enumerate(self.models[f])}
                       for f in FEATURES},
        }

    @classmethod
    def from_dict(cls, data: dict, source: str = "<dict>") -> FeatureModels:
        if not isinstance(data, dict) or "models" not in data:
            raise ValueError(f"{source}: expected a mapping with key 'models'")
        models = {}
        for f in FEATURES:
            per = data["models"].get(f)
            if not isinstance(per, dict):
                raise ValueError(f"{source}: models.{f} missing or not a mapping")  # noqa: TRY004
            row = []
            for p in PART_NAMES:
                if p not in per:
                    raise ValueError(f"{source}: models.{f}.{p} missing")
                try:
                    e = per[p]
                    row.append(FoldedMixture(e["weights"], e["means"], e["sigmas"]))
                except (KeyError, TypeError, ValueError) as exc:
                    raise ValueError(f"{source}: models.{f}.{p}: {exc}") from exc
            models[f] = row
        return cls(models, str(data.get("description", "")))

    @classmethod
    def default(cls) -> FeatureModels:
        """The shipped defaults (fitted on synthetic scenes)."""
        return load_feature_models(None)


def load_feature_models(path: str | Path | None = None) -> FeatureModels:
    """Read models from a YAML file written by ``occbench fit pbm``.

    Args:
        path: YAML file; a bare file name that is no file here names one of the shipped
            models in ``trackers/layered/data/`` (``real_uncompensated.yaml``: fitted on
            real frames, ``tracker=pbm_paper``'s); None = the shipped defaults.
    Raises:
        ValueError naming the file and key when the content is malformed.
    """
    p = DEFAULT_MODELS_PATH if path is None else Path(path)
    if path is not None and p.name == str(path) and not p.is_file():
        p = DEFAULT_MODELS_PATH.with_name(p.name)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ValueError(f"cannot read PBM feature models {p}: {exc}") from exc
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ValueError(f"{p}: invalid YAML: {exc}") from exc
    return FeatureModels.from_dict(data, str(p))


def save_feature_models(models: FeatureModels, path: str | Path, header: str = "") -> None:
    """Write models as YAML with an optional ``#`` comment header."""
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    body = yaml.safe_dump(models.to_dict(), sort_keys=False, default_flow_style=None)
    Path(path).write_text("\n".join(lines) + ("\n" if lines else "") + body)
