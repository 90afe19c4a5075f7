"""The developers' data that the project does not ship (``../shared/data`` beside the
checkout, or beside the main checkout from a worktree under ``wt/``): the benchmark scripts
that read it call ``use_shared_data()`` first, which sets ``$OCCBENCH_SHARED`` unless the
user already did and returns the folder (the library takes it as an argument, e.g.
``occbench.sweeps.generalisation.run_table``'s ``data_root``)."""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def use_shared_data() -> Path:
    """``$OCCBENCH_SHARED``, set to the first existing ``shared/data`` beside the checkout
    (or two levels up) when it is unset; returns it."""
    if not os.environ.get("OCCBENCH_SHARED", "").strip():
        near = [p / "shared" / "data" for p in (ROOT.parent, ROOT.parent.parent)]
        os.environ["OCCBENCH_SHARED"] = str(next((p for p in near if p.is_dir()), near[0]))
    return Path(os.environ["OCCBENCH_SHARED"])
