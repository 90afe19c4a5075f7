"""The two papers' tables rebuilt on our data, with the papers' own figures printed beside.

An experiment config (``conf/experiment/reta_table2.yaml`` ...) holds a ``paper_table`` node:

.. code-block:: yaml

    paper_table:
      name: reta_table2
      title: "Reta et al. 2015, Table 2: ..."
      source: metrics.csv           # or detection_metrics.csv (occbench detect)
      layout: rows                  # rows: one row per method (Reta); columns: one column
                                    # per method, one row per metric (PBM)
      per_sequence: false           # true: one line per (tracker, sequence), else COMBINED
      columns: {Song_GT: GT, "Song_MT%": "MT (%)", ...}   # our column -> the paper's label
      scale: {Precision: 100}       # optional: multiply our column (fractions -> %)
      data_note: "..."              # what our data is (it is not the paper's)
      differences: {data: "...", protocol: "...", annotation: "..."}  # every reason our
                                    # figures can differ from the paper's, by aspect
      test_data: [{sequence: CAVIAR-OneLeaveShop1cor, frames: [151, 295]}, ...]  # scored
      fit_data:                     # everything the table depends on that was fitted or
        - {what: "...", sequence: ..., frames: [1, 150]}   # chosen on data (never a
                                    # test frame: tests/harness/report/test_fit_data.py)
      fit_on_test: [{what: "...", why: "..."}]  # a fit_data entry that does meet the test
                                    # frames, said under the table (choosing-set tables)
      reported:
        citation: "..."             # where the figures come from
        rows: {"<method> (<data>)": [values in the order of `columns`], ...}

``paper_table(metrics, spec)`` builds the table (reported lines labelled ``reported:``, ours
``ours:``); ``write_paper_table(run_dir, spec)`` writes ``paper_table.md`` and
``paper_table.csv`` into the run directory (the ``occbench.sweeps.callbacks.PaperTable`` callback
calls it at the end of the job); ``python -m occbench.report.paper_tables RUN_DIR`` rebuilds
it from a finished run (its ``config.yaml`` holds the spec). The reported figures are the
papers', on the papers' data: they are reference figures, not results of this project.

``combined_dataset`` is a dataset target that concatenates several dataset configs (Reta's
Table 3 spans CAVIAR and PETS 2009).
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
import yaml
from hydra.utils import get_method

from occbench.errors import REFUSED, refusal
from occbench.progress import log_to_stderr

log = logging.getLogger(__name__)

COMBINED = "COMBINED"


class PaperTableError(ValueError):
    """A paper_table spec that cannot be used; the message names the key."""


def combined_dataset(target: str, extra: Mapping[str, Sequence[Any]] | None = None,
                     **kwargs: Any) -> list[Any]:
    """Dataset target: ``target(**kwargs)`` followed by the sequences of ``extra``.

    Used by experiments whose table spans datasets: the experiment selects one dataset config
    (``override /dataset: caviar``), moves its ``_target_`` to ``target`` and sets
    ``_target_`` to this function; ``extra`` maps a label to another dataset config, which
    Hydra instantiates first (so its value arrives as a list of sequences).
    """
    out = list(get_method(target)(**kwargs))
    for label, seqs in (extra or {}).items():
        if seqs is None:
            raise PaperTableError(f"combined_dataset: extra part {label!r} is empty")
        out += list(seqs) if isinstance(seqs, list | tuple) else [seqs]
    return out


def _spec(spec: Mapping[str, Any]) -> dict[str, Any]:
    spec = dict(spec)
    for key in ("title", "columns"):
        if key not in spec:
            raise PaperTableError(f"paper_table.{key} is missing")
    layout = spec.get("layout", "rows")
    if layout not in ("rows", "columns"):
        raise PaperTableError(f"paper_table.layout must be rows or columns, got {layout!r}")
    n = len(spec["columns"])
    for label, values in ((spec.get("reported") or {}).get("rows") or {}).items():
        if len(values) != n:
            raise PaperTableError(
                f"paper_table.reported.rows[{label!r}] has {len(values)} values, "
                f"paper_table.columns has {n}")
    return spec


def paper_table(metrics: pd.DataFrame, spec: Mapping[str, Any]) -> pd.DataFrame:
    """The table: one line per reported method and per our tracker (and sequence).

    Args:
        metrics: our metrics (``tracker``, ``sequence`` + metric columns; ``detection_metrics``
            frames have ``sequence`` and, optionally, ``detector``).
        spec: the ``paper_table`` node (see the module docstring).
    Returns:
        Frame indexed by the line label with the paper's column labels, in ``layout: rows``
        form (``layout: columns`` is applied when writing).
    """
    spec = _spec(spec)
    cols: dict[str, str] = dict(spec["columns"])
    scale: dict[str, float] = dict(spec.get("scale") or {})
    lines: dict[str, list[Any]] = {}
    for label, values in ((spec.get("reported") or {}).get("rows") or {}).items():
        lines[f"reported: {label}"] = list(values)
    rows = metrics
    if "sequence" in rows.columns and not spec.get("per_sequence", False):
        rows = rows[rows["sequence"] == COMBINED]
    missing = [c for c in cols if c not in metrics.columns]
    if missing:
        log.warning("paper table %s: columns not in our metrics: %s", spec.get("name"), missing)
    who = "tracker" if "tracker" in rows.columns else ("detector" if "detector" in rows.columns
                                                      else None)
    note = spec.get("our_label", "")
    for rec in rows.to_dict("records"):
        name = str(rec.get(who, spec.get("method", "ours"))) if who else spec.get("method",
                                                                                   "ours")
        label = f"ours: {name}"
        if spec.get("per_sequence", False) and "sequence" in rec:
            label += f" ({rec['sequence']})"
        elif note:
            label += f" ({note})"
        lines[label] = [rec.get(c, math.nan) * scale.get(c, 1.0)
                        if isinstance(rec.get(c), int | float) else rec.get(c, math.nan)
                        for c in cols]
    return pd.DataFrame.from_dict(lines, orient="index", columns=list(cols.values()))


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return f"{v:.0f}" if v == round(v) and abs(v) >= 10 else f"{v:.3g}"
    return str(v)


def to_markdown(table: pd.DataFrame, spec: Mapping[str, Any]) -> str:
    """The table as Markdown with title, caption and citation."""
    spec = _spec(spec)
    shown = table.T if spec.get("layout", "rows") == "columns" else table
    head = [str(spec.get("row_header", "")) or ("metric" if spec.get("layout") == "columns"
                                                 else "method")]
    lines = [f"## {spec['title']}", ""]
    lines.append("| " + " | ".join(head + [str(c) for c in shown.columns]) + " |")
    lines.append("|" + "---|" * (len(shown.columns) + 1))
    for label, rec in shown.iterrows():
        lines.append("| " + " | ".join([str(label)] + [_fmt(v) for v in rec]) + " |")
    lines.append("")
    if spec.get("caption"):
        lines += [str(spec["caption"]).strip(), ""]
    if spec.get("data_note"):
        lines += [f"Our data: {str(spec['data_note']).strip()}", ""]
    lines += _data_lines(spec)
    if spec.get("differences"):
        lines += ["Why our figures can differ from the paper's:", ""]
        lines += [f"- {aspect}: {str(why).strip()}" for aspect, why in spec["differences"].items()]
        lines.append("")
    cite = (spec.get("reported") or {}).get("citation")
    if cite:
        lines += [(f"Reported figures (labelled `reported:`) are copied from {str(cite).strip()}; "
                  "they were measured by the papers' authors on their data and are shown for "
                  "reference only, not as results of this project."), ""]
    return "\n".join(lines)


def _frames(entry: Mapping[str, Any]) -> str:
    frames = entry.get("frames")
    where = str(entry["sequence"])
    return f"{where} frames {frames[0]}-{frames[1]}" if frames else f"{where} (all frames)"


def _data_lines(spec: Mapping[str, Any]) -> list[str]:
    """The test frames and the fitting data of the table (``test_data``, ``fit_data``)."""
    lines = []
    if spec.get("test_data"):
        lines += ["Test frames: " + "; ".join(_frames(e) for e in spec["test_data"]) + ".", ""]
    if spec.get("fit_data"):
        lines += ["Fitting data (what the table depends on was fitted or chosen there, never on "
                  "a test frame): " + "; ".join(f"{str(e['what']).strip()}: {_frames(e)}"
                                                 for e in spec["fit_data"]) + ".", ""]
    if spec.get("fit_on_test"):
        lines += ["Fitted or chosen on these test frames too (so not untouched): " + "; ".join(
            f"{str(e['what']).strip()} ({str(e['why']).strip()})" for e in spec["fit_on_test"])
            + ".", ""]
    return lines


def write_paper_table(run_dir: str | Path, spec: Mapping[str, Any]) -> Path:
    """Write ``paper_table.md`` and ``paper_table.csv`` into ``run_dir``; returns the .md."""
    run_dir = Path(run_dir)
    source = run_dir / str(spec.get("source", "metrics.csv"))
    if not source.is_file():
        raise FileNotFoundError(f"paper table: {source} not found (did the run score anything?)")
    metrics = pd.read_csv(source)
    if "tracker" not in metrics.columns and spec.get("method"):
        metrics.insert(0, "detector", spec["method"])
    table = paper_table(metrics, spec)
    md = to_markdown(table, spec)
    (run_dir / "paper_table.md").write_text(md)
    shown = table.T if spec.get("layout", "rows") == "columns" else table
    shown.to_csv(run_dir / "paper_table.csv", float_format="%.4f", lineterminator="\n")
    return run_dir / "paper_table.md"


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m occbench.report.paper_tables",
        description="Rebuild paper_table.md of a finished `+experiment=...` run.")
    p.add_argument("run_dir", type=Path, help="run directory holding config.yaml and metrics")
    args = p.parse_args(argv)
    log_to_stderr()
    config = args.run_dir / "config.yaml"
    if not config.is_file():
        config = args.run_dir / ".hydra" / "config.yaml"
    try:
        cfg = yaml.safe_load(config.read_text())
        spec = (cfg or {}).get("paper_table")
        if not spec:
            raise PaperTableError(f"{config}: no paper_table node (run with +experiment=...)")
        path = write_paper_table(args.run_dir, spec)
    except (OSError, ValueError, yaml.YAMLError) as err:
        print(refusal(err), file=sys.stderr)
        return REFUSED
    print(path.read_text(), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
