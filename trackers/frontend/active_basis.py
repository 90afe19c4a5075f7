"""Active-basis shape model of a person (Wu, Si, Gong and Zhu 2010; Reta 3.1's detector).

Wu et al., "Learning Active Basis Model for Object Detection and Recognition", IJCV 90
(2010); section and equation numbers below are theirs.

A template is a small set of Gabor elements ``B_i = B_{x_i, alpha_i}``, i = 1..n, each at a
learnt position x_i (row, column in a template box ``size`` = (H, W) pixels) and orientation
alpha_i (one of ``n_orient`` in [0, pi)), at one Gabor scale. On an image I (a grey patch
cropped around a candidate box and resized so that the box is the template box), each
element may shift along its normal by d in [-b1, b1] pixels and turn by delta in [-b2, b2]
orientation steps (the "active" part, sect. 2.2). Its response is the locally maximal
sigmoid-transformed, normalised Gabor energy (the sum-max architecture, sect. 4.1):

    r(x, alpha)   = (<I, B^cos_{x,alpha}>^2 + <I, B^sin_{x,alpha}>^2) / sigma^2   (sect. 3.5: energy
                    of the sine/cosine pair over its mean sigma^2 on the patch)
    h(r)          = tau (2 / (1 + exp(-2 r / tau)) - 1)                        (eq. 19, tau = 6)
    MAX_i(I)      = max_{d, delta} h(r(x_i + d n_{alpha_i}, alpha_i + delta))  (eq. 25, the max map)

and the template scores the patch by the log-likelihood ratio against background statistics
q(r) (natural-image patches pooled, sect. 3.2):

    score(I) = sum_i [lambda_i MAX_i(I) - log Z(lambda_i)]                     (eq. 22, the sum map)
    Z(lambda) = E_q[exp(lambda h(r))]                                          (eq. 10)

Learning (``active_basis_learn.learn``) is the shared sketch algorithm (sect. 3.3, Algorithm
1; a matching pursuit over M aligned training patches at once): repeatedly pick the element
maximising sum_m MAX(I_m) at (x, alpha), record each image's own perturbed copy (its local argmax),
inhibit in every image the responses of elements overlapping that copy (|<B, B'>|^2 > eps,
the explaining-away step), and fit lambda_i by maximum likelihood:
E_{lambda_i}[h] = mean_m h(r_{m,i}) (eq. 16), with Z from the background histogram of h.

Arrays: patches are (H + 2p, W + 2p) float32 grey levels, p = ``pad`` (the template box
plus room for shifts and kernel support); boxes are xywh float64 pixels of the frame.
``score`` computes the responses only at the pixels it needs (the elements' shifts and a
stride-4 grid for sigma^2) by one matrix product; ``score_maps`` is the plain version with
whole response maps (cv2.filter2D) and the max map, which ``score`` equals to float rounding.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from occbench.trackers.common.checks import at_least, require

TAU = 6.0  # saturation level of the sigmoid h (Wu et al. sect. 3.5)
H_BINS = 64  # bins of the background histogram of h on [0, TAU]
GRID = 4  # stride of the template-box pixels over which sigma^2 is averaged


@dataclass(frozen=True)
class GaborBank:
    """Sine/cosine Gabor pairs at ``n_orient`` orientations of one scale (cv2.getGaborKernel).

    ``theta`` is the direction across the element (its normal); the element itself, an edge
    or bar segment, runs along theta + pi/2. Kernels are zero-mean with unit L2 norm.
    """

    n_orient: int = 12
    ksize: int = 11
    sigma: float = 2.0
    wavelength: float = 6.0
    gamma: float = 0.5

    def __post_init__(self) -> None:
        at_least("bank", 2, n_orient=self.n_orient)
        require("bank.ksize", self.ksize >= 3 and self.ksize % 2 == 1, "must be odd and >= 3",
                self.ksize)

    @property
    def angles(self) -> np.ndarray:
        return np.arange(self.n_orient) * np.pi / self.n_orient

    def kernels(self) -> np.ndarray:
        """(n_orient, 2, k, k) float32: [cosine, sine] kernel of each orientation."""
        out = np.zeros((self.n_orient, 2, self.ksize, self.ksize), dtype=np.float32)
        for a, theta in enumerate(self.angles):
            for j, psi in enumerate((0.0, np.pi / 2)):
                g = cv2.getGaborKernel((self.ksize, self.ksize), self.sigma, float(theta),
                                       self.wavelength, self.gamma, psi, ktype=cv2.CV_64F)
                g -= g.mean()
                out[a, j] = g / np.linalg.norm(g)
        return out


def sigmoid(r: np.ndarray) -> np.ndarray:
    """h(r) = tau (2 / (1 + exp(-2 r / tau)) - 1), Wu et al. eq. 19."""
    return TAU * (2.0 / (1.0 + np.exp(-2.0 * np.asarray(r) / TAU)) - 1.0)


def shift_offsets(bank: GaborBank, b1: int) -> np.ndarray:
    """(n_orient, 2 b1 + 1, 2) int: (row, col) offsets d n_alpha, d = -b1..b1, along each
    orientation's normal (theta: column = cos theta, row = sin theta; rows point down)."""
    d = np.arange(-b1, b1 + 1)
    th = bank.angles
    return np.stack([np.rint(d[None] * np.sin(th)[:, None]), np.rint(d[None] * np.cos(th)[:, None])],
                    axis=-1).astype(np.int64)


@dataclass
class ActiveBasis:
    """A learnt template: elements and their exponential-family parameters.

    Attributes:
        size: (H, W) template box, pixels.
        rows, cols: (n,) int element positions in the template box.
        orient: (n,) int orientation indices.
        lam: (n,) lambda_i (eq. 16).
        log_z: (n,) log Z(lambda_i) (eq. 10).
        bank: the Gabor scale and orientations.
        b1: shift range along the normal, pixels; b2: turn range, orientation steps.
        background_h: (H_BINS,) background histogram q of h (probabilities), kept with the
            template for provenance and drawing.
    """

    size: tuple[int, int]
    rows: np.ndarray
    cols: np.ndarray
    orient: np.ndarray
    lam: np.ndarray
    log_z: np.ndarray
    bank: GaborBank = field(default_factory=GaborBank)
    b1: int = 2
    b2: int = 1
    background_h: np.ndarray | None = None

    def __post_init__(self) -> None:
        H, W = (int(v) for v in self.size)
        self.size = (H, W)
        self.rows, self.cols = np.asarray(self.rows, np.int64), np.asarray(self.cols, np.int64)
        self.orient = np.asarray(self.orient, np.int64)
        self.lam, self.log_z = np.asarray(self.lam, np.float64), np.asarray(self.log_z, np.float64)
        n = len(self.rows)
        if not (len(self.cols) == len(self.orient) == len(self.lam) == len(self.log_z) == n) or n == 0:
            raise ValueError("ActiveBasis: rows, cols, orient, lam, log_z must be non-empty and of equal length")
        if (self.rows < 0).any() or (self.rows >= H).any() or (self.cols < 0).any() or (self.cols >= W).any():
            raise ValueError(f"ActiveBasis: element positions outside the template box {self.size}")
        if (self.orient < 0).any() or (self.orient >= self.bank.n_orient).any():
            raise ValueError(f"ActiveBasis: orientation indices outside [0, {self.bank.n_orient})")
        A, k, p = self.bank.n_orient, self.bank.ksize, self.pad
        kern = self.bank.kernels().reshape(A, 2, k * k)  # (A, [cos, sin], k*k)
        self._turns = (self.orient[:, None] + np.arange(-self.b2, self.b2 + 1)[None]) % A  # (n, turns)
        # each element's kernels: its turned orientations' pairs, (n, k*k, 2 * turns)
        self._elem_kernels = np.ascontiguousarray(
            kern[self._turns].reshape(self.n, -1, k * k).transpose(0, 2, 1))
        self._grid_kernels = np.ascontiguousarray(kern.reshape(2 * A, k * k).T)  # (k*k, 2A)
        # flat patch indices of the k x k windows ``score`` needs, centred on: every
        # element's shifts along its normal (n, shifts), and the sigma^2 grid (stride GRID)
        Wp = self.patch_shape[1]
        win = (np.arange(k)[:, None] * Wp + np.arange(k)[None]).ravel()  # window offsets
        off = shift_offsets(self.bank, self.b1)[self.orient]  # (n, shifts, 2)
        er = self.rows[:, None] + off[..., 0] + p - k // 2  # window top-left rows
        ec = self.cols[:, None] + off[..., 1] + p - k // 2
        self._elem_index = (er * Wp + ec)[..., None] + win  # (n, shifts, k*k)
        gr, gc = np.meshgrid(*(np.arange(0, n, GRID) + p - k // 2 for n in self.size), indexing="ij")
        self._grid_index = (gr.reshape(-1) * Wp + gc.reshape(-1))[:, None] + win  # (G, k*k)

    @property
    def n(self) -> int:
        return len(self.rows)

    @property
    def pad(self) -> int:
        """Margin of a patch around the template box: shifts plus half a kernel."""
        return self.b1 + self.bank.ksize // 2

    @property
    def patch_shape(self) -> tuple[int, int]:
        H, W = self.size
        return H + 2 * self.pad, W + 2 * self.pad

    # ------------------------------------------------------------------ scoring
    def score(self, patch: np.ndarray) -> float:
        """Log-likelihood ratio of a (H + 2 pad, W + 2 pad) grey patch (eq. 22)."""
        return float(self.scores(np.asarray(patch, np.float32)[None])[0])

    def scores(self, patches: np.ndarray) -> np.ndarray:
        """(B,) log-likelihood ratios of (B, H + 2 pad, W + 2 pad) grey patches (eq. 22), one
        gather and two matrix products for the batch."""
        patches = np.asarray(patches, dtype=np.float32)
        if patches.ndim != 3 or patches.shape[1:] != self.patch_shape:
            raise ValueError(f"score: patch must be {self.patch_shape}, got {patches.shape[1:]}")
        B = len(patches)
        flat = patches.reshape(B, -1)
        g = flat[:, self._grid_index] @ self._grid_kernels  # (B, G, 2A): <I, B^cos>, <I, B^sin>
        sigma2 = (g * g).mean(axis=(1, 2)) * 2.0 + 1e-6  # sect. 3.5: mean energy over x, alpha
        c = np.matmul(flat[:, self._elem_index], self._elem_kernels)  # (B, n, shifts, 2 turns)
        c *= c
        r = c[..., 0::2] + c[..., 1::2]  # energies (B, n, shifts, turns)
        m = sigmoid(r.reshape(B, self.n, -1).max(axis=2) / sigma2[:, None])  # eq. 25: MAX_i
        return (self.lam * m - self.log_z).sum(axis=1)  # eq. 22

    def score_maps(self, patch: np.ndarray) -> float:
        """The same score from whole response maps (cv2.filter2D) and the max map: the plain
        form of the sum-max computation, for checking ``score``."""
        maps = response_maps(np.asarray(patch, np.float32), self.bank, self.size, self.pad)
        mx = max_map(sigmoid(maps), self.bank, self.b1, self.b2)  # (A, H, W)
        m = mx[self.orient, self.rows, self.cols]
        return float((self.lam * m - self.log_z).sum())

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Plain arrays for ``np.savez`` (see ``from_arrays``)."""
        b = self.bank
        return {
            "size": np.asarray(self.size, np.int64), "rows": self.rows, "cols": self.cols,
            "orient": self.orient, "lam": self.lam, "log_z": self.log_z,
            "bank": np.asarray([b.n_orient, b.ksize, b.sigma, b.wavelength, b.gamma], np.float64),
            "perturb": np.asarray([self.b1, self.b2], np.int64),
            "background_h": (np.zeros(H_BINS) if self.background_h is None else self.background_h),
        }

    @classmethod
    def from_arrays(cls, a) -> ActiveBasis:
        n_orient, ksize, sigma, wl, gamma = (float(v) for v in a["bank"])
        bank = GaborBank(int(n_orient), int(ksize), sigma, wl, gamma)
        b1, b2 = (int(v) for v in a["perturb"])
        return cls(tuple(int(v) for v in a["size"]), a["rows"], a["cols"], a["orient"], a["lam"],
                   a["log_z"], bank, b1, b2, np.asarray(a["background_h"], np.float64))


# ---------------------------------------------------------------------- response maps
def response_maps(patch: np.ndarray, bank: GaborBank, size: tuple[int, int], pad: int) -> np.ndarray:
    """(A, H + 2 pad', W + 2 pad') normalised energies r over the template box and b1 around it.

    Returned maps are indexed so that [a, row, col] is template position (row, col) (the box
    starts at ``pad - b1`` ... see below): rows/cols of the returned arrays are the template
    box's, extended by ``pad - ksize // 2`` (the shift margin) on each side.
    """
    K = bank.kernels()
    k2 = bank.ksize // 2
    H, W = size
    e = pad - k2  # shift margin kept around the box
    out = np.empty((bank.n_orient, H + 2 * e, W + 2 * e), np.float32)
    for a in range(bank.n_orient):
        c = cv2.filter2D(patch, cv2.CV_32F, K[a, 0], borderType=cv2.BORDER_REFLECT)
        s = cv2.filter2D(patch, cv2.CV_32F, K[a, 1], borderType=cv2.BORDER_REFLECT)
        out[a] = (c * c + s * s)[k2 : k2 + H + 2 * e, k2 : k2 + W + 2 * e]
    sigma2 = float(out[:, e : e + H : GRID, e : e + W : GRID].mean()) + 1e-6  # sect. 3.5
    return out / sigma2


def max_map(hmaps: np.ndarray, bank: GaborBank, b1: int, b2: int) -> np.ndarray:
    """(A, H, W) max map over shifts along the normal and turns (eq. 25).

    ``hmaps`` is (..., A, H + 2 b1, W + 2 b1) (the template box with the shift margin); the
    result is over the template box only: out[a, y, x] = max_{d, delta}
    hmaps[a + delta, y + b1 + d n_a]. Leading axes (a stack of images) are kept.
    """
    off = shift_offsets(bank, b1)
    A = bank.n_orient
    H, W = hmaps.shape[-2] - 2 * b1, hmaps.shape[-1] - 2 * b1
    out = np.full(hmaps.shape[:-3] + (A, H, W), -np.inf, dtype=hmaps.dtype)
    for a in range(A):
        for dy, dx in off[a]:
            for t in range(-b2, b2 + 1):
                sl = hmaps[..., (a + t) % A, b1 + dy : b1 + dy + H, b1 + dx : b1 + dx + W]
                np.maximum(out[..., a, :, :], sl, out=out[..., a, :, :])
    return out


# ---------------------------------------------------------------------- patches
def crop_patch(grey: np.ndarray, box, size: tuple[int, int], pad: int) -> np.ndarray:
    """The (H + 2 pad, W + 2 pad) float32 grey patch of a (rows, cols) grey or (rows, cols, 3)
    BGR uint8 image in which the xywh
    ``box`` becomes the template box ``size`` (H, W): the box plus its share of ``pad``
    around it, resized (INTER_AREA shrinking, linear enlarging); outside the image the
    border is replicated."""
    H, W = size
    x, y, w, h = (float(v) for v in box)
    sx, sy = w / W, h / H
    x0, y0 = x - pad * sx, y - pad * sy
    x1, y1 = x + w + pad * sx, y + h + pad * sy
    c0, r0 = int(np.floor(x0)), int(np.floor(y0))
    c1, r1 = int(np.ceil(x1)), int(np.ceil(y1))
    R, C = grey.shape[:2]
    crop = grey[max(r0, 0) : max(min(r1, R), 0), max(c0, 0) : max(min(c1, C), 0)]
    if crop.size == 0:
        return np.zeros((H + 2 * pad, W + 2 * pad), np.float32)
    t, b = max(-r0, 0), max(r1 - R, 0)
    le, ri = max(-c0, 0), max(c1 - C, 0)
    if t or b or le or ri:
        crop = cv2.copyMakeBorder(crop, t, b, le, ri, cv2.BORDER_REPLICATE)
    shape = (W + 2 * pad, H + 2 * pad)
    interp = cv2.INTER_AREA if crop.shape[0] > shape[1] else cv2.INTER_LINEAR
    out = cv2.resize(crop, shape, interpolation=interp)
    if out.ndim == 3:  # BGR: grey levels of the patch only, never of the whole frame
        out = cv2.cvtColor(out, cv2.COLOR_BGR2GRAY)
    return out.astype(np.float32)
