"""The run directory, written as results arrive: ``RunWriter`` and the ``Failure`` records
it appends to ``errors.txt``."""

from __future__ import annotations

import csv
import io
import logging
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from harness.datasets.base import Sequence
from harness.errors import RunError
from harness.io.mot import (
    MotTable,
    write_atomic,
    write_mot,
    write_mot_gt,
    write_seqinfo,
    write_seqmap,
)

log = logging.getLogger(__name__)


@dataclass
class Failure:
    """One failed piece of a run: ``tracker`` is '*' when the whole sequence failed."""

    tracker: str
    sequence: str
    stage: str
    message: str
    trace: str = ""


class RunWriter:
    """Writes a run directory as results arrive, so that a later failure loses nothing.

    Layout: ``config.yaml`` (resolved config), ``tracks/<tracker>/<sequence>.txt`` (MOT
    results, written as each tracker finishes a sequence), ``gt/<sequence>/gt/gt.txt`` and
    ``gt/<sequence>/seqinfo.ini`` (the ground truth scored against, before the trackers run)
    with ``gt/seqmap.txt`` (the sequences tracked so far): a MOTChallenge benchmark folder
    that TrackEval re-scores as it is; ``metrics.csv`` and ``summary.md`` (rewritten after
    each sequence), ``timings.csv``, ``errors.txt`` (only when something failed),
    ``summary.tex`` (COMBINED LaTeX table), ``hota_alpha.csv`` (HOTA and its sub-metrics at
    each alpha) and ``plots/`` (``metrics.png``, ``hota_alpha.png``) at the end.
    """

    #: outputs of an earlier run in the same folder, removed when a run starts there so that
    #: nothing stale (a track file of a tracker or sequence not run again) is mistaken for
    #: this run's; files of sweeps (status.json) and Hydra (.hydra/, the log) are kept
    STALE = ("tracks", "metrics.csv", "summary.md", "summary.tex", "timings.csv", "errors.txt",
             "plots/metrics.png", "config.yaml")

    def __init__(self, out_dir: str | Path) -> None:
        self.out_dir = Path(out_dir)
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            for stale in self.STALE:
                path = self.out_dir / stale
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                else:
                    path.unlink(missing_ok=True)
            for part in self.out_dir.rglob("*.part"):
                part.unlink(missing_ok=True)
        except OSError as err:
            raise RunError(f"cannot prepare the run folder {self.out_dir}: "
                           f"{err.strerror or err} ({err.filename or self.out_dir})") from None

    def track_path(self, tracker: str, sequence: str) -> Path:
        return self.out_dir / "tracks" / tracker / f"{sequence}.txt"

    def tracks(self, tracker: str, sequence: str, table: MotTable) -> Path:
        """Write a tracker's result file (raises ``WriteError`` naming it)."""
        path = self.track_path(tracker, sequence)
        write_mot(path, table.frames, table.ids, table.boxes, table.conf)
        return path

    def ground_truth(self, seq: Sequence) -> Path | None:
        """Write ``gt/<sequence>/gt/gt.txt`` (``write_mot_gt``) and its ``seqinfo.ini``; None
        when the sequence has no ground truth."""
        if seq.gt is None:
            return None
        folder = self.out_dir / "gt" / seq.info.name
        write_mot_gt(folder / "gt" / "gt.txt", seq.gt.table)
        info = seq.info
        write_seqinfo(folder / "seqinfo.ini", info.name, info.length, info.fps, info.width,
                      info.height)
        return folder / "gt" / "gt.txt"

    def seqmap(self, names: list[str]) -> Path:
        """Write ``gt/seqmap.txt`` naming ``names``."""
        path = self.out_dir / "gt" / "seqmap.txt"
        write_seqmap(path, names)
        return path

    def metrics(self, frame: pd.DataFrame) -> None:
        write_atomic(self.out_dir / "metrics.csv", frame.to_csv(
            index=False, float_format="%.6f", lineterminator="\n"))

    def timings(self, rows: list[dict[str, Any]]) -> None:
        buf = io.StringIO()
        w = csv.DictWriter(buf, ["tracker", "sequence", "frames", "seconds", "fps"],
                           lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        write_atomic(self.out_dir / "timings.csv", buf.getvalue())

    def failure(self, f: Failure) -> None:
        """Append ``f`` to errors.txt; a failure to write it is logged, never raised (the
        failure is in the run's result and its log all the same)."""
        text = f"[{f.stage}] tracker={f.tracker} sequence={f.sequence}: {f.message}\n"
        if f.trace:
            text += "    " + f.trace.rstrip().replace("\n", "\n    ") + "\n"
        try:
            with (self.out_dir / "errors.txt").open("a") as fh:
                fh.write(text)
        except OSError as err:
            log.error("cannot write %s: %s", self.out_dir / "errors.txt", err.strerror or err)

    def text(self, name: str, text: str) -> Path:
        return write_atomic(self.out_dir / name, text)
