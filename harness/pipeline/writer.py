"""The run directory, written as results arrive: ``RunWriter`` and the ``Failure`` records
it appends to ``errors.txt``."""

from __future__ import annotations

import csv
import errno
import io
import logging
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from occbench.config.rundir import busy
from occbench.datasets.base import Sequence
from occbench.errors import RunError
from occbench.io.mot import MotTable
from occbench.io.write import (
    WriteError,
    write_atomic,
    write_mot,
    write_mot_gt,
    write_seqinfo,
    write_seqmap,
)

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)

RESERVE_FILE = ".occbench-reserve"  # removed at the end of every run
RESERVE_BYTES = 1 << 20  # freed on a full disk: room for metrics.csv, summary.md, errors.txt


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
    results, written as each tracker finishes a sequence; under the single-target protocol
    with ``<sequence>.followers.csv`` beside it), ``gt/<sequence>/gt/gt.txt`` and
    ``gt/<sequence>/seqinfo.ini`` (the ground truth scored against, before the trackers run)
    with ``gt/seqmap.txt`` (the sequences tracked so far): a MOTChallenge benchmark folder
    that TrackEval re-scores as it is; ``metrics.csv`` and ``summary.md`` (rewritten after
    each sequence), ``timings.csv``, ``errors.txt`` (only when something failed),
    ``summary.tex`` (COMBINED LaTeX table), ``hota_alpha.csv`` (HOTA and its sub-metrics at
    each alpha), ``plots/`` (``metrics.png``, ``hota_alpha.png``) and ``report.html``
    (``occbench.report.html``) at the end.
    """

    #: everything a run writes into its folder, by top-level name: the writer, the plots,
    #: ``occbench report`` (report/, plots/) and the paper-table callback write nowhere
    #: else (``path`` refuses any other name; a test checks a real run and report against
    #: it). A run starting in a used folder removes all of it first, so nothing of an
    #: earlier run (a track file, a gt/ sequence, a plot of a tracker not run again) is
    #: mistaken for this run's; Hydra's files (.hydra/, the log), a sweep's status.json
    #: and the run lock are not the writer's and stay.
    OWNED = ("config.yaml", "tracks", "gt", "metrics.csv", "summary.md", "summary.tex",
             "timings.csv", "errors.txt", "hota_alpha.csv", "plots", "report",
             "paper_table.md", "paper_table.csv", "report.html")

    def __init__(self, out_dir: str | Path) -> None:
        self.out_dir = Path(out_dir)
        owner = busy(self.out_dir)
        if owner is not None:
            raise RunError(f"run folder {self.out_dir} is in use by a live run ({owner}): "
                           "wait for it to end or choose another folder")
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise RunError(f"run folder {self.out_dir} is an existing file, not a folder")
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            for name in self.OWNED:
                path = self.out_dir / name
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                else:
                    path.unlink(missing_ok=True)
            for part in [*self.out_dir.rglob("*.part"), *self.out_dir.rglob("*.part.*")]:
                part.unlink(missing_ok=True)
        except OSError as err:
            raise RunError(f"cannot prepare the run folder {self.out_dir}: "
                           f"{err.strerror or err} ({err.filename or self.out_dir})") from None

        self.failures: list[Failure] = []
        self._reserve = self.out_dir / RESERVE_FILE

    def reserve(self) -> None:
        """Set disk space aside for the run's own account (metrics.csv, summary.md,
        errors.txt) when the disk fills up (see ``_write``); ``close`` gives it back."""
        try:
            self._reserve.write_bytes(b"\0" * RESERVE_BYTES)
        except OSError:
            self._reserve.unlink(missing_ok=True)

    def close(self) -> None:
        """Give back the reserved space (at the end of a run, however it ends)."""
        self._reserve.unlink(missing_ok=True)

    def _write(self, name: str, text: str) -> Path:
        """``write_atomic`` of ``name``; on a full disk the reserve is given up and the write
        tried once more, so that metrics.csv, summary.md and errors.txt of what was done are
        written even when a track file or a plot before them filled the disk."""
        try:
            return write_atomic(self.out_dir / name, text)
        except WriteError as err:
            if err.errno != errno.ENOSPC or not self._reserve.exists():
                raise
            log.warning("disk full: the space reserved for the run's own account is used")
            self._reserve.unlink(missing_ok=True)
            return write_atomic(self.out_dir / name, text)

    def path(self, name: str) -> Path:
        """The path of output ``name`` (relative, e.g. ``plots/metrics.png``) in the folder.

        Raises:
            ValueError: ``name`` is not under one of ``OWNED`` (a new output must be declared
                there, or a later run in the folder would keep a stale copy of it).
        """
        top = Path(name).parts[0] if name else ""
        if top not in self.OWNED:
            raise ValueError(f"{name}: not an output of RunWriter.OWNED {self.OWNED}")
        return self.out_dir / name

    def track_path(self, tracker: str, sequence: str) -> Path:
        return self.out_dir / "tracks" / tracker / f"{sequence}.txt"

    def followers(self, tracker: str, sequence: str, followers: dict[int, int]) -> Path:
        """Write ``tracks/<tracker>/<sequence>.followers.csv`` (``id,follower``: the
        single-target protocol's reported id -> the id its follower started under)."""
        path = self.track_path(tracker, sequence).with_suffix(".followers.csv")
        rows = "".join(f"{i},{f}\n" for i, f in sorted(followers.items()))
        write_atomic(path, "id,follower\n" + rows)
        return path

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
        self._write("metrics.csv", frame.to_csv(
            index=False, float_format="%.6f", lineterminator="\n"))

    def timings(self, rows: list[dict[str, Any]]) -> None:
        buf = io.StringIO()
        w = csv.DictWriter(buf, ["tracker", "sequence", "frames", "seconds", "fps"],
                           lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        self._write("timings.csv", buf.getvalue())

    def failure(self, f: Failure) -> None:
        """Add ``f`` to errors.txt, rewritten whole (atomically) with every failure so far,
        so it is never cut short; a failure to write it is logged, never raised (the failure
        is in the run's result and its log all the same)."""
        self.failures.append(f)
        text = "".join(_entry(e) for e in self.failures)
        try:
            self._write("errors.txt", text)
        except OSError as err:
            log.error("%s", err)

    def text(self, name: str, text: str) -> Path:
        return self._write(name, text)


def _entry(f: Failure) -> str:
    text = f"[{f.stage}] tracker={f.tracker} sequence={f.sequence}: {f.message}\n"
    if f.trace:
        text += "    " + f.trace.rstrip().replace("\n", "\n    ") + "\n"
    return text
