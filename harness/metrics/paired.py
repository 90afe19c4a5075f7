"""Paired comparisons: the difference of two trackers' IDF1, HOTA and MOTA on the same
frames, with a block-bootstrap interval.

What is resampled: each sequence's frames are cut into consecutive blocks of ``block``
frames (the last one shorter); a resample draws, within every sequence, as many blocks as it
has, with replacement (a stratified bootstrap of non-overlapping blocks: every sequence keeps its
weight, and frames stay together in blocks, so that the temporal correlation of a track's
errors is kept inside a block). Both trackers get the same draw: the difference is paired.
Each resample sums the drawn frames' counts (``occbench.metrics.timeline.FrameCounts``) over
all sequences and recomputes MOTA, IDF1 and HOTA from the sums, as a COMBINED row is
(``timeline.scores``). The matching, the identity mapping and HOTA's association scores are
the whole run's, not re-solved per resample (the interval is conditional on them).

The interval is the percentile interval of the ``resamples`` differences (``level``, 95% by
default), from ``numpy.random.default_rng(seed)``: the same run gives the same interval.
A difference whose interval contains 0 is not distinguishable on this data.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from occbench.metrics.arrays import distinct
from occbench.metrics.timeline import FrameCounts, scores

METRICS = ("IDF1", "HOTA", "MOTA")
BLOCK = 10  # frames per block
RESAMPLES = 1000
SEED = 0
LEVEL = 0.95


@dataclass(frozen=True)
class PairedDifference:
    """``a``'s ``metric`` minus ``b``'s on the same frames, with its bootstrap interval.

    Attributes:
        a, b: the two names compared (trackers, or sweep settings).
        metric: IDF1, HOTA or MOTA.
        value_a, value_b: the metric of each on all the frames (their COMBINED values).
        low, high: the percentile interval of the difference.
        sequences, frames: what was resampled (sequences in common, frames in them).
    """

    a: str
    b: str
    metric: str
    value_a: float
    value_b: float
    low: float
    high: float
    sequences: int
    frames: int

    @property
    def difference(self) -> float:
        return self.value_a - self.value_b

    @property
    def distinguishable(self) -> bool:
        """False when the interval contains 0 (or is undefined)."""
        return bool(np.isfinite(self.low) and np.isfinite(self.high)
                    and (self.low > 0 or self.high < 0))


@dataclass(frozen=True)
class Bootstrap:
    """The resampling scheme (module docstring): ``block`` frames per block, ``resamples``
    draws from ``default_rng(seed)``, a ``level`` percentile interval."""

    block: int = BLOCK
    resamples: int = RESAMPLES
    seed: int = SEED
    level: float = LEVEL

    def __post_init__(self) -> None:
        if self.block < 1:
            raise ValueError(f"block must be at least 1 frame, got {self.block}")
        if self.resamples < 2:
            raise ValueError(f"resamples must be at least 2, got {self.resamples}")
        if not 0.0 < self.level < 1.0:
            raise ValueError(f"level must be in (0, 1), got {self.level}")

    def describe(self) -> str:
        """One sentence saying what is resampled."""
        return (f"{self.level:.0%} percentile interval of {self.resamples} paired block-"
                f"bootstrap resamples (blocks of {self.block} consecutive frames drawn with "
                f"replacement within each sequence, the same draw for both; seed "
                f"{self.seed}); matching and association are the whole run's")

    def compare(self, a: Mapping[str, FrameCounts], b: Mapping[str, FrameCounts],
                names: tuple[str, str] = ("a", "b"),
                metrics: Sequence[str] = METRICS) -> list[PairedDifference]:
        """The paired differences ``a - b`` over the sequences both were scored on.

        Args:
            a, b: sequence -> per-frame counts of each side.
        Raises:
            ValueError: no sequence in common, or an unknown metric.
        """
        bad = [m for m in metrics if m not in METRICS]
        if bad:
            raise ValueError(f"paired metrics must be among {METRICS}, got {bad}")
        common = [s for s in a if s in b]
        if not common:
            raise ValueError(f"{names[0]} and {names[1]} share no scored sequence")
        rng = np.random.default_rng(self.seed)
        draws_a, draws_b, full_a, full_b, n_frames = [], [], 0.0, 0.0, 0
        for s in common:
            ma, mb = aligned(a[s], b[s])
            n_frames += len(ma)
            full_a, full_b = full_a + ma.sum(0), full_b + mb.sum(0)
            starts = np.arange(0, len(ma), self.block)
            if len(starts) == 0:
                continue
            blocks_a, blocks_b = np.add.reduceat(ma, starts), np.add.reduceat(mb, starts)
            picks = rng.integers(0, len(starts), size=(self.resamples, len(starts)))
            flat = picks + len(starts) * np.arange(self.resamples)[:, None]
            weights = np.bincount(flat.ravel(), minlength=self.resamples * len(starts)
                                  ).reshape(self.resamples, len(starts))  # draws per block
            draws_a.append(weights @ blocks_a)
            draws_b.append(weights @ blocks_b)
        sa, sb = scores(np.sum(draws_a, axis=0)), scores(np.sum(draws_b, axis=0))
        va, vb = scores(full_a), scores(full_b)
        tail = 100 * (1 - self.level) / 2
        out = []
        for m in metrics:
            diff = sa[m] - sb[m]
            diff = diff[np.isfinite(diff)]
            low, high = (np.percentile(diff, [tail, 100 - tail]) if len(diff)
                         else (np.nan, np.nan))
            out.append(PairedDifference(names[0], names[1], m, float(va[m]), float(vb[m]),
                                        float(low), float(high), len(common), n_frames))
        return out


def aligned(a: FrameCounts, b: FrameCounts) -> tuple[np.ndarray, np.ndarray]:
    """(F, D) count matrices of ``a`` and ``b`` on the union of their frames (a frame one
    side lacks had no box of it and no gt: zero counts), in frame order."""
    frames = distinct(a.frames, b.frames)
    out = []
    for c in (a, b):
        m = np.zeros((len(frames), c.matrix().shape[1]))
        m[np.searchsorted(frames, c.frames)] = c.matrix()
        out.append(m)
    return out[0], out[1]


def all_pairs(counts: Mapping[str, Mapping[str, FrameCounts]],
              bootstrap: Bootstrap | None = None) -> list[PairedDifference]:
    """Every pair of trackers (in the mapping's order, first minus second) that share a
    scored sequence; ``counts``: tracker -> sequence -> per-frame counts."""
    boot = bootstrap or Bootstrap()
    out: list[PairedDifference] = []
    for x, y in combinations([n for n, c in counts.items() if c], 2):
        if any(s in counts[y] for s in counts[x]):
            out += boot.compare(counts[x], counts[y], (x, y))
    return out
