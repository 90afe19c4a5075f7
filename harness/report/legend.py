"""What each column of ``summary.md`` means: one line per column, written once under the
tables (``column_legend``), only for the columns the summary shows.

The definitions are those of the code that computes them: CLEAR MOT and identity
(``occbench.metrics``), HOTA (Luiten et al. 2021, computed as TrackEval does), the occlusion columns
(``occbench.metrics.occlusion``) and the two papers' trajectory metrics
(``occbench.metrics.paper``: Song et al. as Reta et al. 2015 report them, and PBM 5.2).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

COLUMNS: dict[str, str] = {
    "HOTA": "higher order tracking accuracy, sqrt(DetA x AssA) averaged over IoU thresholds "
            ".05-.95 (Luiten et al. 2021)",
    "DetA": "HOTA's detection accuracy: TP / (TP + FN + FP), averaged over IoU thresholds",
    "AssA": "HOTA's association accuracy: how well matched boxes keep one identity",
    "LocA": "HOTA's localisation accuracy: mean IoU of the matched boxes",
    "DetRe": "HOTA's detection recall: TP / (TP + FN), averaged over IoU thresholds",
    "DetPr": "HOTA's detection precision: TP / (TP + FP), averaged over IoU thresholds",
    "AssRe": "HOTA's association recall: of a person's matches, the share under its id",
    "AssPr": "HOTA's association precision: of an id's matches, the share on its person",
    "IDF1": "identity F1: frames where the one-to-one best id mapping holds, "
            "2 IDTP / (2 IDTP + IDFP + IDFN) (Ristani et al. 2016)",
    "IDP": "identity precision: IDTP / (IDTP + IDFP)",
    "IDR": "identity recall: IDTP / (IDTP + IDFN)",
    "MOTA": "1 - (FN + FP + IDs) / gt boxes (CLEAR MOT; may be negative)",
    "MOTP": "mean IoU of the matched boxes (CLEAR MOT, here as an overlap: higher is better)",
    "Recall": "matched gt boxes / gt boxes",
    "Precision": "matched boxes / reported boxes",
    "GT": "ground-truth trajectories (people)",
    "MT": "mostly tracked: people matched in more than 80% of their frames",
    "PT": "partly tracked: people matched in 20-80% of their frames",
    "ML": "mostly lost: people matched in less than 20% of their frames",
    "FP": "false positives: reported boxes matched to no person",
    "FN": "false negatives (misses): gt boxes matched to no reported box",
    "IDs": "identity switches: a person matched to another id than at its last match",
    "Frag": "fragmentations: a person's tracking interrupted and resumed",
    "ReID": "re-identified after total occlusion: episodes whose first match after the "
            "occlusion has the id of the last one before it / scored episodes",
    "ReID_frames": "mean frames from reappearance to that first correct match (0 = at once)",
    "ReID_n": "scored total-occlusion episodes",
    "Song_GT": "Song et al. (Reta Table 1): ground-truth trajectories",
    "Song_MT%": "Song et al.: % of trajectories covered more than 80% of the time",
    "Song_PT%": "Song et al.: % covered 20-80% of the time",
    "Song_ML%": "Song et al.: % covered less than 20% of the time",
    "Song_Frag": "Song et al.: times the matched id changes along a gt trajectory",
    "Song_IDS": "Song et al.: times a result trajectory's matched person changes",
    "PBM_GT": "PBM 5.2: ground-truth trajectories",
    "PBM_MT": "PBM: trajectories tracked more than 80% of their frames",
    "PBM_MT1": "PBM: of those, tracked under one single id throughout",
    "PBM_ML": "PBM: trajectories tracked less than 40% of their frames",
    "PBM_Missed": "PBM: trajectories never matched",
    "PBM_Under": "PBM under-segmented: first id matched to a person had already followed "
                 "another person",
    "PBM_Over": "PBM over-segmented: trajectories matched by more than one id",
    "PBM_IDsw/traj": "PBM: id swaps between two people (an id taken from another person) "
                     "per trajectory",
    "PBM_IDs/traj": "PBM: distinct ids per matched trajectory (should be one)",
    "PBM_IDs/frame": "PBM multiple responses: distinct ids answering a gt box per frame "
                     "(should be one)",
    "PBM_dx%": "PBM Tables 2-4: mean |x error| of the box centre, % of the gt width",
    "PBM_dy%": "PBM: mean |y error| of the box centre, % of the gt height",
    "PBM_dw%": "PBM: mean |width error|, % of the gt width",
    "PBM_dh%": "PBM: mean |height error|, % of the gt height",
}
# per ground-truth visibility bin: Recall_v0-25, IDP_v25-50, IDs_v75-100, ...
BINNED = re.compile(r"^(Recall|IDP|IDs)_v(\d+)-(\d+)$")


def meaning(column: str) -> str | None:
    """One line saying what ``column`` is, or None for a column this module does not know."""
    if column in COLUMNS:
        return COLUMNS[column]
    m = BINNED.match(column)
    if m is None:
        return None
    what = {"Recall": "recall", "IDP": "identity precision of the matched boxes",
            "IDs": "identity switches"}[m.group(1)]
    return (f"{what} over the gt boxes {m.group(2)}-{m.group(3)}% visible (occlusion by "
            "visibility)")


def column_legend(columns: Iterable[str]) -> list[str]:
    """Markdown lines of a ``## Columns`` section: each known column once, in order of
    first appearance; unknown columns are listed as such rather than guessed."""
    seen = list(dict.fromkeys(c for c in columns if c not in ("tracker", "sequence")))
    if not seen:
        return []
    lines = ["## Columns", ""]
    for c in seen:
        text = meaning(c)
        lines.append(f"- `{c}`: {text}" if text else f"- `{c}`: (not described here)")
    return [*lines, ""]
