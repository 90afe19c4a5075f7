"""Evaluation metrics: CLEAR MOT, identity (IDF1) and HOTA, per sequence and combined.

Public API::

    score = score_sequence(gt, res, iou_threshold=0.5)   # gt, res: occbench.io.mot.MotTable
    table = summarize({"seq-a": score_a, "seq-b": score_b})

``summarize`` returns one row per sequence plus a ``COMBINED`` row, columns ``sequence`` +
``COLUMNS``. Ratios are fractions (not percent); MOTP is the mean IoU of matched pairs.
The combined row sums the counts of all sequences and recomputes every ratio from the sums
(MOTA is never averaged); HOTA is combined as TrackEval does (TP/FN/FP summed per alpha,
AssA and LocA weighted by the TP counts). Which gt and tracker rows are scored is decided
in ``occbench.metrics.frames`` (MOTChallenge devkit ignore rules).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from occbench.io.mot import MotTable
from occbench.metrics.clear import ClearCounts, clear_counts
from occbench.metrics.frames import pair_frames
from occbench.metrics.hota import ALPHAS, HotaCounts, combine_hota, hota_counts

if TYPE_CHECKING:  # pandas is imported where used (start-up time)
    import pandas as pd

__all__ = [
    "COLUMNS",
    "COMBINED",
    "COUNT_COLUMNS",
    "HOTA_ALPHA_COLUMNS",
    "SequenceScore",
    "combine",
    "hota_alpha_table",
    "score_sequence",
    "summarize",
]

COLUMNS: list[str] = [
    "MOTA", "MOTP", "IDF1", "IDP", "IDR", "Recall", "Precision",
    "GT", "MT", "PT", "ML", "FP", "FN", "IDs", "Frag",
    "HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr",
]  # fmt: skip
#: per-alpha columns of ``hota_alpha_table`` (each also averaged over alpha in ``COLUMNS``)
HOTA_ALPHA_COLUMNS: list[str] = ["HOTA", "DetA", "AssA", "DetRe", "DetPr", "AssRe", "AssPr",
                                 "LocA"]
COUNT_COLUMNS: list[str] = ["GT", "MT", "PT", "ML", "FP", "FN", "IDs", "Frag"]
COMBINED = "COMBINED"


@dataclass
class SequenceScore:
    """Everything needed to report one sequence and to combine it with others.

    Attributes:
        clear: additive CLEAR/ID counts.
        hota: HOTA per-alpha counts.
        iou_threshold: IoU threshold used for CLEAR/ID matching.
        ignored_gt: gt rows not scored (conf 0 or non-pedestrian class).
        removed_tracker: tracker rows removed for matching a distractor-class gt box.
    """

    clear: ClearCounts
    hota: HotaCounts
    iou_threshold: float = 0.5
    ignored_gt: int = 0
    removed_tracker: int = 0

    def row(self) -> dict[str, float | int]:
        """The values of ``COLUMNS`` for this score."""
        c = self.clear
        out: dict[str, float | int] = dict(c.ratios())
        out.update(
            GT=c.unique_objects, MT=c.mostly_tracked, PT=c.partially_tracked, ML=c.mostly_lost,
            FP=c.false_positives, FN=c.misses, IDs=c.switches, Frag=c.fragmentations,
        )  # fmt: skip
        h = self.hota.summary()
        out.update(h)  # HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe, AssPr (means over alpha)
        return {k: out[k] for k in COLUMNS}


def score_sequence(gt: MotTable, res: MotTable, iou_threshold: float = 0.5) -> SequenceScore:
    """Score one sequence.

    Args:
        gt: ground truth from ``read_mot(path, gt=True)``; boxes (N, 4) xywh 0-based.
        res: tracker output from ``read_mot(path)``; boxes (M, 4) xywh 0-based.
        iou_threshold: smallest IoU of a CLEAR/ID match, in (0, 1]. HOTA does not use it
            (it averages over its own thresholds 0.05..0.95).
    Raises:
        ValueError: bad threshold, or an id repeated within a frame (names the file).
    """
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold!r}")
    pairs = pair_frames(gt, res)  # one IoU matrix per frame, read by every metric
    return SequenceScore(
        clear=clear_counts(pairs, iou_threshold),
        hota=hota_counts(pairs),
        iou_threshold=iou_threshold,
        ignored_gt=pairs.ignored_gt,
        removed_tracker=pairs.removed_tracker,
    )


def combine(scores: Mapping[str, SequenceScore] | list[SequenceScore]) -> SequenceScore:
    """Combined score: counts summed, HOTA combined as TrackEval."""
    parts = list(scores.values()) if isinstance(scores, Mapping) else list(scores)
    thresholds = {s.iou_threshold for s in parts}
    if len(thresholds) > 1:
        raise ValueError(f"cannot combine scores with different IoU thresholds {thresholds}")
    clear = ClearCounts()
    for s in parts:
        clear = clear + s.clear
    return SequenceScore(
        clear=clear,
        hota=combine_hota([s.hota for s in parts]),
        iou_threshold=thresholds.pop() if thresholds else 0.5,
        ignored_gt=sum(s.ignored_gt for s in parts),
        removed_tracker=sum(s.removed_tracker for s in parts),
    )


def summarize(scores: Mapping[str, SequenceScore]) -> pd.DataFrame:
    """One row per sequence (in the mapping's order) plus a ``COMBINED`` row.

    Returns:
        DataFrame with columns ``sequence`` + ``COLUMNS``; count columns are int64, ratios
        float64 fractions (NaN where undefined, e.g. MOTA without gt).
    Raises:
        ValueError: no scores, or a sequence named ``COMBINED``.
    """
    if not scores:
        raise ValueError("summarize needs at least one sequence score")
    if COMBINED in scores:
        raise ValueError(f"a sequence may not be named {COMBINED!r}")
    rows = [{"sequence": name, **s.row()} for name, s in scores.items()]
    rows.append({"sequence": COMBINED, **combine(scores).row()})
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    table = pd.DataFrame(rows, columns=["sequence", *COLUMNS])
    table[COUNT_COLUMNS] = table[COUNT_COLUMNS].astype("int64")
    return table


def hota_alpha_table(scores: Mapping[str, SequenceScore]) -> pd.DataFrame:
    """HOTA and its sub-metrics at each of the 19 alphas (``occbench.metrics.hota.ALPHAS``).

    Returns:
        DataFrame with columns ``sequence``, ``alpha`` + ``HOTA_ALPHA_COLUMNS``: 19 rows per
        sequence (in the mapping's order) and 19 for ``COMBINED`` (combined as TrackEval);
        fractions. Their means over alpha are the same columns of ``summarize``.
    """
    import pandas as pd  # start-up: pandas, ~0.25 s CPU

    parts = [*scores.items(), (COMBINED, combine(scores))]
    frames = []
    for name, s in parts:
        h = s.hota
        values = {"HOTA": h.hota, "DetA": h.det_a, "AssA": h.ass_a, "DetRe": h.det_re,
                  "DetPr": h.det_pr, "AssRe": h.ass_re, "AssPr": h.ass_pr, "LocA": h.loc_a}
        frames.append(pd.DataFrame({"sequence": name, "alpha": np.round(ALPHAS, 2),
                                    **{k: values[k] for k in HOTA_ALPHA_COLUMNS}}))
    return pd.concat(frames, ignore_index=True)
