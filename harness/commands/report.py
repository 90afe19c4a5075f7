"""``occbench report RUN_DIR`` (``python -m occbench.report RUN_DIR``): the pictures of a
finished run, written into the run directory.

* ``report/<sequence>.mp4`` and ``report/<sequence>_sheet.png``: every tracker of the run
  drawn its own way, side by side (``occbench.replay.video``; the trackers are run again with
  the run's saved config, so the drawings show the run's tracks);
* ``plots/trajectory_<sequence>_<person>.png``: the most occluded ground-truth person's path
  beside the ids that followed it (``occbench.replay.trajectories``; none for a sequence
  without ground truth);
* printed: the tracks per tracker and sequence, their lengths and frames/s
  (``occbench.report.tracks``), with or without ground truth;
* ``report.html`` written again (``occbench.report.html``), now with the video playing beside
  the error timelines and the new plots.

Each part can be skipped (``--no-video``, ``--no-trajectories``); ``--sequence`` picks the
sequence (default: the run's first). For other outputs use the two modules directly.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from occbench.commands.mistakes import refuse
from occbench.progress import log_to_stderr
from occbench.replay import trajectories, video
from occbench.report.html import write_run_report
from occbench.report.tracks import counted, tracks_text


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="occbench report",
        description="Video, contact sheet and trajectory plot of a finished run, written "
                    "into the run directory (report/, plots/).")
    p.add_argument("run_dir", type=Path, help="run directory of occbench run")
    p.add_argument("--sequence", help="sequence name (default: the run's first)")
    p.add_argument("--frames", type=int, nargs=2, metavar=("FIRST", "LAST"),
                   help="frame range of the video (default: all)")
    p.add_argument("--no-gt", action="store_true", help="do not draw the ground truth")
    p.add_argument("--no-video", action="store_true", help="skip the video and contact sheet")
    p.add_argument("--no-trajectories", action="store_true", help="skip the trajectory plot")
    args = p.parse_args(argv)
    log_to_stderr()  # the page's own lines (e.g. a failed paired comparison) in LOG_FORMAT

    if not (args.run_dir / "config.yaml").is_file():
        return refuse(f"{args.run_dir / 'config.yaml'} not found (a run directory of "
                      "occbench run)")
    if not (args.run_dir / "tracks").is_dir():
        errors = args.run_dir / "errors.txt"
        return refuse(f"{args.run_dir / 'tracks'} not found: the run wrote no tracks"
                      + (f" (it failed: {errors})" if errors.is_file() else ""))
    common = ["--sequence", args.sequence] if args.sequence else []
    status = 0
    if not args.no_video:
        extra = [*common, *(["--no-gt"] if args.no_gt else [])]
        if args.frames:
            extra += ["--frames", *map(str, args.frames)]
        status = max(status, video.main(["--run", str(args.run_dir), *extra]))
    if not args.no_trajectories:
        status = max(status, trajectories.main([str(args.run_dir), *common]))
    if (args.run_dir / "metrics.csv").is_file():  # the page again, with the video and plots

        seq = args.sequence or _first_sequence(args.run_dir)
        first = {seq: args.frames[0]} if args.frames else None
        try:
            print(f"page: {write_run_report(args.run_dir, first=first)}")
        except (OSError, ValueError) as err:
            status = max(status, refuse(f"report.html: {err}"))
    print(tracks_text(counted(args.run_dir)), end="")
    return status


def _first_sequence(run_dir: Path) -> str:
    """The run's first sequence (``gt/seqmap.txt``: a header, then one name a line), the one
    the video shows without ``--sequence``."""
    path = run_dir / "gt" / "seqmap.txt"
    names = path.read_text().split()[1:] if path.is_file() else []
    return names[0] if names else ""


if __name__ == "__main__":
    sys.exit(main())
