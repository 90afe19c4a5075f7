"""Writing matplotlib figures the same way everywhere."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def save_figure(fig: Any, path: str | Path) -> Path:
    """Lay ``fig`` out, write it to ``path`` (folders made as needed) without the
    matplotlib-version metadata, so the same run writes the same bytes, and close it."""
    import matplotlib.pyplot as plt  # start-up: matplotlib.pyplot, ~0.4 s CPU

    fig.tight_layout()
    path = Path(path)
    tmp = path.with_name(f"{path.stem}.part{path.suffix}")  # whole file or none (disk full)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(tmp, metadata={"Software": None})
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        plt.close(fig)
    return path
