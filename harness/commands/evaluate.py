"""Score MOT result files against ground truth: ``occbench eval GT RESULTS``.

GT is a gt file or a folder, either in MOTChallenge layout (``<seq>/gt/gt.txt``) or flat
(``<seq>.txt``); a nested folder with a ``seqmap.txt`` (a run folder's ``gt/``) is scored
on the sequences it lists only. RESULTS is a result file or a folder of ``<seq>.txt`` files. A sequence
without a result file is scored as an empty result (a warning is logged); a folder with no
result file but tracker folders that hold some (a run's ``tracks/``) is refused, naming them. The table (one
row per sequence and a ``COMBINED`` row; ratios as fractions with 3 decimals, as the app
prints them) is printed, and written as CSV with ``--csv`` (6 decimals). Exit status 0 on
success, 1 on a path or file it refuses (one line ``occbench: ...`` naming it).
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from occbench.commands.mistakes import refuse
from occbench.datasets.mot import read_seqinfo, seqinfo_number
from occbench.io.mot import MotTable, read_mot
from occbench.metrics import COLUMNS, COUNT_COLUMNS, SequenceScore, score_sequence, summarize
from occbench.progress import log_to_stderr
from occbench.report.tables import number

log = logging.getLogger(__name__)


class EvaluationInputError(ValueError):
    """GT or RESULTS paths that cannot be paired; the message names the path."""


def sequence_name(gt_file: Path) -> str:
    """``<seq>/gt/gt.txt`` or ``<seq>/gt.txt`` -> ``<seq>``; ``<seq>.txt`` -> ``<seq>``."""
    if gt_file.name == "gt.txt":
        parent = gt_file.resolve().parent
        return parent.parent.name if parent.name == "gt" else parent.name
    return gt_file.stem


def find_gt(gt: Path) -> dict[str, Path]:
    """Sequence name -> gt file, for a gt file or folder (sorted by name).

    Raises:
        FileNotFoundError: ``gt`` does not exist.
        EvaluationInputError: a folder with no gt files in either layout.
    """
    if not gt.exists():
        raise FileNotFoundError(f"ground truth not found: {gt}")
    if gt.is_file():
        return {sequence_name(gt): gt}
    nested = sorted(gt.glob("*/gt/gt.txt"))
    if nested:
        return listed({p.parent.parent.name: p for p in nested}, gt / "seqmap.txt")
    flat = sorted(p for p in gt.glob("*.txt") if p.is_file())
    if not flat:
        raise EvaluationInputError(
            f"{gt}: no ground truth found (expected <seq>/gt/gt.txt or <seq>.txt)"
        )
    return {p.stem: p for p in flat}


def listed(found: dict[str, Path], seqmap: Path) -> dict[str, Path]:
    """``found`` restricted to the sequences ``seqmap`` names (MOTChallenge's seqmap file: a
    header line, then one sequence a line), when there is one: a run folder's gt/ holds the
    gt of a sequence an interrupted run began but never finished, and its seqmap names only
    those tracked (scoring the other would score a result the run never wrote).

    Raises:
        EvaluationInputError: the seqmap names a sequence without ``<seq>/gt/gt.txt``.
    """
    if not seqmap.is_file():
        return found
    names = [line.strip() for line in seqmap.read_text().splitlines()[1:] if line.strip()]
    missing = [n for n in names if n not in found]
    if missing:
        raise EvaluationInputError(f"{seqmap} names {', '.join(missing)} but there is no "
                                   f"{seqmap.parent / missing[0] / 'gt' / 'gt.txt'}")
    left = sorted(set(found) - set(names))
    if left:
        log.warning("%s: %s not listed, not scored", seqmap, ", ".join(left))
    return {n: p for n, p in found.items() if n in names}


def pair_files(gt: Path, results: Path) -> dict[str, tuple[Path, Path | None]]:
    """Sequence name -> (gt file, result file or None when missing).

    Raises:
        FileNotFoundError: ``gt`` or ``results`` does not exist.
        EvaluationInputError: a single result file against several gt sequences, or a
            folder of tracker folders (a run's tracks/) in place of one of them.
    """
    gt_files = find_gt(gt)
    if not results.exists():
        raise FileNotFoundError(f"results not found: {results}")
    if results.is_file():
        if len(gt_files) != 1:
            raise EvaluationInputError(
                f"{results} is one file but {gt} holds {len(gt_files)} sequences; "
                "give a results folder with <seq>.txt files"
            )
        ((name, g),) = gt_files.items()
        return {name: (g, results)}
    if not any((results / f"{name}.txt").is_file() for name in gt_files):
        holders = sorted(d.name for d in results.iterdir()
                         if d.is_dir() and any((d / f"{n}.txt").is_file() for n in gt_files))
        if holders:  # a run's tracks/: one folder per tracker, no result file of its own
            raise EvaluationInputError(
                f"{results} holds no result file but one folder per tracker "
                f"({', '.join(holders)}): give one, e.g. {results / holders[0]}")
    pairs: dict[str, tuple[Path, Path | None]] = {}
    for name, g in gt_files.items():
        r = results / f"{name}.txt"
        pairs[name] = (g, r if r.is_file() else None)
    extra = sorted(p.stem for p in results.glob("*.txt") if p.stem not in gt_files and p.is_file())
    if extra:
        log.warning("%s: result files without ground truth ignored: %s", results, ", ".join(extra))
    return pairs


def _sequence_info(gt_file: Path) -> tuple[int | None, tuple[int, int] | None]:
    """``seqLength`` and (``imWidth``, ``imHeight``) of the ``seqinfo.ini`` beside a
    ``<seq>/gt/gt.txt``, each None when absent.

    Raises:
        SeqInfoError: a seqinfo.ini that cannot be read or whose seqLength or frame size is
            not a positive integer (file and key named): rows past it would go unchecked.
    """
    ini = gt_file.parent.parent / "seqinfo.ini"
    if gt_file.name != "gt.txt" or not ini.is_file():
        return None, None
    info = read_seqinfo(ini)
    size = tuple(seqinfo_number(info, key, ini, int) for key in ("imWidth", "imHeight"))
    return seqinfo_number(info, "seqLength", ini, int), None if None in size else size


def evaluate(gt: str | Path, results: str | Path, iou_threshold: float = 0.5) -> pd.DataFrame:
    """Score all sequences; returns ``summarize`` of the scores (fractions, COMBINED row)."""
    scores: dict[str, SequenceScore] = {}
    for name, (g, r) in pair_files(Path(gt), Path(results)).items():
        last_frame, image = _sequence_info(g)  # rows past the last frame are errors
        gt_table = read_mot(g, gt=True, last_frame=last_frame, image=image)
        if r is None:
            log.warning(
                "%s: no result file %s; scored as an empty result",
                name,
                Path(results) / f"{name}.txt",
            )
            res_table = MotTable.empty(str(Path(results) / f"{name}.txt"))
        else:
            res_table = read_mot(r, kind="result", last_frame=last_frame, image=image)
        scores[name] = score_sequence(gt_table, res_table, iou_threshold)
        log.debug(
            "%s: scored %d gt rows against %d result rows", name, len(gt_table), len(res_table)
        )
    return summarize(scores)


def format_table(table: pd.DataFrame) -> str:
    """The table as text: ratios as fractions with 3 decimals, counts as integers."""
    ratios = [c for c in COLUMNS if c not in COUNT_COLUMNS]
    formatters = {c: number for c in ratios}  # the tables' one rule
    return table.to_string(index=False, formatters=formatters, na_rep="-")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="occbench eval",
        description="CLEAR MOT, IDF1 and HOTA of MOT result files against ground truth.",
    )
    p.add_argument("gt", type=Path, help="gt file, or folder of <seq>/gt/gt.txt or <seq>.txt")
    p.add_argument("results", type=Path, help="result file, or folder of <seq>.txt")
    p.add_argument("--csv", type=Path, default=None, help="write the table here")
    p.add_argument(
        "--iou",
        type=float,
        default=0.5,
        help="IoU threshold of a CLEAR/ID match, in (0, 1] (default 0.5)",
    )
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    log_to_stderr()
    try:
        table = evaluate(args.gt, args.results, args.iou)
    except (FileNotFoundError, ValueError) as err:  # MotFormatError is a ValueError

        return refuse(err)
    print(f"IoU threshold {args.iou:g}; ratios as fractions")
    print(format_table(table))
    if args.csv is not None:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        table.to_csv(args.csv, index=False, float_format="%.6f", lineterminator="\n")
        log.info("wrote %s", args.csv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
