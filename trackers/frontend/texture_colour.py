"""A per-pixel mixture over local texture and illumination-invariant colour (Reta 3.1).

Reta et al. 3.1 model the background with "a mixture of Gaussian probability map that uses
local texture features and invariant color features" (their ref. 29: Yao and Odobez 2007,
multi-layer background subtraction based on colour and texture). This is that model in the
form the reference gives it, vectorised over the image:

* every pixel keeps K modes m_k = (mu_k, t_k, w_k): a colour mean mu_k (3,), a texture
  descriptor t_k (8,) and a weight w_k;
* texture is a scale-invariant local ternary pattern (SILTP, Liao et al. 2010): for each of the
  8 neighbours n at ``texture_radius`` of the grey level g, s_n = +1 if g_n > (1 + tau) g,
  -1 if g_n < (1 - tau) g, else 0 (with a floor of ``noise`` / 2 grey levels on tau g, so that
  sensor noise in dark regions does not flip it). Multiplying the image by a factor (a cast shadow, a gain
  change) leaves s unchanged, and a faint pattern (a floor reflection, contrast below tau)
  does not flip it. t_k is the running mean of s; the distance is
      D_tex = mean_n |s_n - t_kn| / 2                                       in [0, 1];
* colour is compared after removing brightness (Horprasert et al. 1999; Kim's codebook):
  with the brightness ratio a = I . mu / |mu|^2 and the chromatic distortion
  c = |I - a mu| / (a |mu|),
      D_col = min(c / chroma_tolerance, 1)   if shadow_ratio <= a <= highlight_ratio,
      D_col = 1                              otherwise,
  and D_col = 0 when |I - mu| is under ``noise`` grey levels (dark pixels have no stable
  chromaticity). A cast shadow (a in [shadow_ratio, 1), same chromaticity) matches;
* a pixel matches a mode when D = lambda D_tex + (1 - lambda) D_col < ``threshold`` (Yao and
  Odobez eq. 3-4), and the strongest (largest w_k) of the modes it matches is taken; the matched mode is updated with rate alpha (w_k <- (1 - alpha) w_k
  + alpha, mu_k and t_k move by alpha towards the observation), the others decay
  (w_k <- (1 - alpha) w_k); without a match, the weakest mode is replaced by the observation
  with weight alpha;
* a pixel is background when its matched mode's weight is at least ``background_weight``
  (a mode seen in that share of the recent frames), else foreground.

``apply`` returns OpenCV's convention: 255 foreground, 127 background explained only by the
invariance (matched although the plain colour differs by more than ``noise``: shadows and
faint reflections, drawn for inspection), 0 background. The numpy code below is the
reference; ``compiled`` runs the same equations as one numba pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from occbench.trackers.common.checks import (
    at_least,
    coerce,
    parameter_group,
    refuse_moved,
    require,
    unit,
)

#: (dy, dx) of the 8 neighbours, clockwise from the top-left
_NEIGHBOURS = ((-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1))


def siltp(grey: np.ndarray, tau: float, radius: int = 1, floor: float = 0.0) -> np.ndarray:
    """Scale-invariant local ternary pattern of a (H, W) float32 grey image.

    Returns (8, H, W) float32 in {-1, 0, 1}: +1 where neighbour n is brighter than the centre
    g by more than max(tau g, floor), -1 where darker by more than that (edge-replicated).
    ``floor`` (grey levels) keeps sensor noise in dark regions from flipping the pattern.
    """
    r = int(radius)
    g = np.pad(grey, r, mode="edge")
    H, W = grey.shape
    out = np.empty((8, H, W), dtype=np.float32)
    step = np.maximum(grey * tau, floor)
    hi, lo = grey + step, grey - step
    for n, (dy, dx) in enumerate(_NEIGHBOURS):
        nb = g[r + dy * r : r + dy * r + H, r + dx * r : r + dx * r + W]
        np.subtract(nb > hi, nb < lo, out=out[n], dtype=np.float32)
    return out


@dataclass(frozen=True)
class Texture:
    """The texture term: SILTP and its share of the distance D.

    Args:
        texture_weight: lambda, share of the texture distance in D.
        texture_tau: SILTP's relative tolerance tau.
        texture_radius: SILTP neighbour distance, pixels of the working image.
    """

    texture_weight: float = 0.5
    texture_tau: float = 0.08
    texture_radius: int = 1

    def __post_init__(self) -> None:
        g = "background.mixture.texture"
        unit(g, texture_weight=self.texture_weight)
        require(f"{g}.texture_tau", 0.0 < self.texture_tau < 1.0, "must lie in (0, 1)",
                self.texture_tau)
        at_least(g, 1, texture_radius=self.texture_radius)
        coerce(self, {"texture_weight": float, "texture_tau": float, "texture_radius": int})


@dataclass(frozen=True)
class Colour:
    """The invariant-colour term D_col.

    Args:
        chroma_tolerance: chromatic distortion at which D_col reaches 1.
        shadow_ratio: darkest brightness ratio a still matched (cast shadows).
        highlight_ratio: brightest ratio a still matched.
        noise: grey levels of |I - mu| under which the colour always matches.
    """

    chroma_tolerance: float = 0.12
    shadow_ratio: float = 0.5
    highlight_ratio: float = 1.15
    noise: float = 12.0

    def __post_init__(self) -> None:
        g = "background.mixture.colour"
        require(f"{g}.chroma_tolerance", self.chroma_tolerance > 0, "must be > 0",
                self.chroma_tolerance)
        require(f"{g}.shadow_ratio", 0.0 < self.shadow_ratio <= 1.0, "must lie in (0, 1]",
                self.shadow_ratio)
        at_least(g, 1, highlight_ratio=self.highlight_ratio)
        at_least(g, 0, noise=self.noise)
        coerce(self, {"chroma_tolerance": float, "shadow_ratio": float,
                      "highlight_ratio": float, "noise": float})


@dataclass(frozen=True)
class ModeMatch:
    """When an observation matches a mode, and when that mode is background.

    Args:
        threshold: largest D of a match.
        background_weight: smallest weight of a background mode.
    """

    threshold: float = 0.4
    background_weight: float = 0.3

    def __post_init__(self) -> None:
        g = "background.mixture.matching"
        require(f"{g}.threshold", 0.0 < self.threshold <= 1.0, "must lie in (0, 1]",
                self.threshold)
        require(f"{g}.background_weight", 0.0 < self.background_weight < 1.0,
                "must lie in (0, 1)", self.background_weight)
        coerce(self, {"threshold": float, "background_weight": float})


#: the mixture's groups: its argument -> the group's class
GROUPS = {"texture": Texture, "colour": Colour, "matching": ModeMatch}


class TextureColourMixture:
    """Per-pixel K-mode mixture over SILTP texture and invariant colour (see module docstring).

    Same calling convention as OpenCV's background subtractors: ``apply(frame,
    learningRate)`` returns the (H, W) uint8 label (255 / 127 / 0) and updates the model;
    ``getBackgroundImage()`` gives the strongest mode's colour.

    Args:
        modes: K, modes per pixel.
        history: frames of memory; the default rate alpha is 1 / history.
        texture: the texture term (``Texture``).
        colour: the invariant-colour term (``Colour``).
        matching: a match and a background mode (``ModeMatch``).
        compiled: run ``apply`` as one compiled pass (``_texture_colour_kernel``, tested
            against this numpy code); False runs the numpy equations below.
        Each group is its defaults when None; a key of the flat arguments before the groups
        is refused with a TypeError naming its group.
    """

    def __init__(self, modes: int = 3, history: int = 500, texture: Texture | None = None,
                 colour: Colour | None = None, matching: ModeMatch | None = None,
                 compiled: bool = True, **moved: object) -> None:
        refuse_moved("background.mixture", moved, GROUPS)
        at_least("background.mixture", 1, modes=modes, history=history)
        self.modes, self.history = int(modes), int(history)
        self.texture = parameter_group("texture", texture, Texture)
        self.colour = parameter_group("colour", colour, Colour)
        self.matching = parameter_group("matching", matching, ModeMatch)
        self.compiled = bool(compiled)
        # pixel-major, as the compiled pass reads them; the numpy code below works on their
        # (K, N, ...) transposed views
        self._mu: np.ndarray | None = None  # (N, K, 3) colour means
        self._t: np.ndarray | None = None  # (N, K, 8) texture means
        self._w: np.ndarray | None = None  # (N, K) weights
        self._shape: tuple[int, int] | None = None

    def reset(self) -> None:
        """Forget the learnt background."""
        self._mu = self._t = self._w = None
        self._shape = None

    def _init(self, colour: np.ndarray, tex: np.ndarray, shape: tuple[int, int]) -> None:
        K, N = self.modes, colour.shape[0]
        self._shape = shape
        self._mu = np.repeat(colour[:, None], K, axis=1)
        self._t = np.repeat(tex.T[:, None], K, axis=1)
        self._w = np.zeros((N, K), dtype=np.float32)
        self._w[:, 0] = 1.0

    def _modes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """mu (K, N, 3), t (K, N, 8), w (K, N): views of the model, mode-major."""
        return self._mu.transpose(1, 0, 2), self._t.transpose(1, 0, 2), self._w.T

    def distances(self, colour: np.ndarray, tex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """D (K, N) of each observation to each mode, and whether D_col relied on the
        invariance (K, N) bool (plain colour difference above ``noise``)."""
        mu, t, _ = self._modes()
        # D_tex = mean_n |s_n - t_kn| / 2
        d_tex = np.abs(tex.T[None] - t).mean(axis=2) * 0.5
        # brightness ratio a = I.mu / |mu|^2, chromatic distortion c = |I - a mu| / (a |mu|)
        mu2 = np.einsum("knc,knc->kn", mu, mu) + 1.0
        a = np.einsum("nc,knc->kn", colour, mu) / mu2
        diff = colour[None] - a[..., None] * mu
        c = np.sqrt(np.einsum("knc,knc->kn", diff, diff) / (a * a * mu2 + 1e-6))
        plain = colour[None] - mu
        col = self.colour
        far = np.einsum("knc,knc->kn", plain, plain) > 3.0 * col.noise**2
        d_col = np.minimum(c / col.chroma_tolerance, 1.0)
        d_col[(a < col.shadow_ratio) | (a > col.highlight_ratio)] = 1.0
        d_col[~far] = 0.0
        lam = self.texture.texture_weight
        return lam * d_tex + (1.0 - lam) * d_col, far

    def apply(self, frame: np.ndarray, learningRate: float = -1.0) -> np.ndarray:  # noqa: N803
        """Label a (H, W, 3) uint8 frame (255 fg, 127 explained by invariance, 0 bg) and
        update the model with rate ``learningRate`` (-1: 1 / history; 0: no update)."""
        H, W = frame.shape[:2]
        alpha = 1.0 / self.history if learningRate < 0 else float(learningRate)
        tx, col, match = self.texture, self.colour, self.matching
        if self.compiled and self._mu is not None and self._shape == (H, W):
            # start-up: the numba kernels (~8 ms CPU), for the compiled model only
            from occbench.trackers.frontend._texture_colour_kernel import apply_kernel

            label = np.empty((H, W), dtype=np.uint8)
            apply_kernel(np.ascontiguousarray(frame), self._mu, self._t, self._w, alpha,
                         tx.texture_tau, tx.texture_radius, 0.5 * col.noise,
                         tx.texture_weight, match.threshold, match.background_weight,
                         col.chroma_tolerance, col.shadow_ratio, col.highlight_ratio,
                         col.noise, label)
            return label
        colour = frame.reshape(-1, 3).astype(np.float32)
        grey = colour.mean(axis=1).reshape(H, W) + 1.0
        tex = siltp(grey, tx.texture_tau, tx.texture_radius, 0.5 * col.noise).reshape(8, -1)
        if self._mu is None or self._shape != (H, W):
            self._init(colour, tex, (H, W))
            return np.zeros((H, W), dtype=np.uint8)
        d, far = self.distances(colour, tex)
        N = colour.shape[0]
        cols = np.arange(N)
        mu, t, w = self._modes()
        ok = d < match.threshold
        k = np.argmax(np.where(ok, w, -1.0), axis=0)  # the strongest matching mode
        matched = ok[k, cols]
        is_bg = matched & (w[k, cols] >= match.background_weight)
        label = np.where(is_bg, np.where(far[k, cols], 127, 0), 255).astype(np.uint8)
        if alpha > 0:
            w *= 1.0 - alpha
            mk, mc = k[matched], cols[matched]
            w[mk, mc] += alpha
            mu[mk, mc] += alpha * (colour[mc] - mu[mk, mc])
            t[mk, mc] += alpha * (tex[:, mc].T - t[mk, mc])
            new = np.flatnonzero(~matched)
            if len(new):  # replace the weakest mode
                kn = np.argmin(w[:, new], axis=0)
                w[kn, new] = alpha
                mu[kn, new] = colour[new]
                t[kn, new] = tex[:, new].T
        return label.reshape(H, W)

    def getBackgroundImage(self) -> np.ndarray | None:  # noqa: N802
        """(H, W, 3) uint8 colour of each pixel's strongest mode, or None before any frame."""
        if self._mu is None:
            return None
        k = np.argmax(self._w, axis=1)
        img = self._mu[np.arange(self._mu.shape[0]), k]
        return np.clip(img + 0.5, 0, 255).astype(np.uint8).reshape(*self._shape, 3)
