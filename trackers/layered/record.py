"""How long an unfound target is reported, by the camera's record (``reported_by_record``).

pbm reports a confirmed target unfound for at most ``reporting.max_misses`` frames (5): past
that a person standing or walking behind another goes unreported (68 of synth-tune's 254
missed boxes), while before it a person who has left is reported where he is not. Whether a
target unfound for m frames is still there is a property of the camera (doorways, scenery,
how long people stand behind one another), so ``ReportedByRecord`` keeps one record per
sequence: every episode of a confirmed target unfound for g frames ends either found again
(a success for m = 1..g when the found box overlaps the box it was last reported at, IoU >=
0.5: the report would have been on the person) or dropped (a failure for m = 1..g). A
confirmed target unfound for m > ``reporting.max_misses`` frames is reported too while the
resolved episodes that lasted m frames or more were successes at least half the time (the
IDF1 break-even of one more box, near 0.5 at the figures these sets have); without such an
episode it is not. Reporting only: no target lives longer. Boxes are (N, 4) float64 xywh.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from occbench.trackers.geometry import iou_matrix


@dataclass
class ReportedByRecord:
    """``adaptations.reported_by_record`` (module docstring). ``successes[m]`` /
    ``episodes[m]``: resolved episodes that lasted >= m frames, found again where reported /
    all."""

    successes: dict[int, int] = field(default_factory=dict)
    episodes: dict[int, int] = field(default_factory=dict)
    _open: dict[int, tuple[int, np.ndarray]] = field(default_factory=dict)  # id -> (g, box)

    def reset(self) -> None:
        self.successes.clear()
        self.episodes.clear()
        self._open.clear()

    def _resolve(self, g: int, success: bool) -> None:
        for m in range(1, g + 1):
            self.episodes[m] = self.episodes.get(m, 0) + 1
            self.successes[m] = self.successes.get(m, 0) + int(success)

    def observe(self, targets, found: np.ndarray, report_box) -> None:
        """End the episodes of targets found again or dropped since the last frame; note the
        box each confirmed unfound target would be reported at (``report_box``)."""
        ids = targets.id.tolist()
        row_of = {tid: r for r, tid in enumerate(ids)}
        for tid, (g, box) in list(self._open.items()):
            r = row_of.get(tid)
            if r is None:
                self._resolve(g, False)
            elif found[r]:
                self._resolve(g, iou_matrix(box[None], targets.boxes[r][None])[0, 0] >= 0.5)
            else:
                continue
            del self._open[tid]
        rows = (targets.confirmed & ~found).nonzero()[0]
        if len(rows):
            boxes = targets.boxes[rows]
            report_box.place(boxes, targets, rows, found)
            for r, box in zip(rows.tolist(), boxes):
                self._open[ids[r]] = (int(targets.misses[r]), box.copy())

    def shown(self, targets, found: np.ndarray, shown: np.ndarray, report_box,
              fg: np.ndarray | None) -> np.ndarray:
        """(T,) bool: ``shown`` (found, or confirmed and unfound <= ``reporting.max_misses``)
        with the confirmed unfound targets whose run of misses the record supports added."""
        self.observe(targets, found, report_box)
        rows = (targets.confirmed & ~shown).nonzero()[0]
        if not len(rows):
            return shown
        out = shown.copy()
        for r in rows.tolist():
            m = int(targets.misses[r])
            n = self.episodes.get(m, 0)
            out[r] = n > 0 and 2 * self.successes.get(m, 0) >= n
        return out
