"""Where the project's data lives: one data root, resolved against the installed project.

The root is ``datasets/`` of the project checkout (found from this package's location, so
the current directory does not matter; installed as the README says), or the
folder named by the environment variable ``OCCBENCH_DATA`` when it is set (a relative value
is taken against the current directory when it is read). Its layout::

    <root>/CAVIAR-OneLeaveShop1cor/   OneLeaveShop1cor.mpg, seqinfo.ini, gt/ (shipped)
    <root>/trajectories/<sequence>/  PETS09-S2L1, TUD-Campus, CAVIAR-OneLeaveShop2cor (shipped)
    <root>/<anything you download>   e.g. MOT17/train/<sequence>/ (git-ignored)

Configs name files under the root with the ``occbench.data`` resolver
(``root: ${occbench.data:CAVIAR-OneLeaveShop1cor}``), registered by
``occbench.config.register_resolvers()``.
"""

from __future__ import annotations

import os
from pathlib import Path

from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict

#: The one environment variable that moves the data root.
DATA_ENV = "OCCBENCH_DATA"

#: The repository root of this installation (holds conf/, datasets/, harness/, trackers/).
PROJECT_ROOT = Path(__file__).resolve().parents[2]

#: The data shipped with the repository (see datasets/README.md).
SHIPPED_DATA = PROJECT_ROOT / "datasets"

#: The resolver name configs use: ``${occbench.data:relative/path}``.
RESOLVER = "occbench.data"


def data_root() -> Path:
    """The data root: ``$OCCBENCH_DATA`` (made absolute) if set and non-empty, else ``datasets/``
    of the project checkout."""
    env = os.environ.get(DATA_ENV, "").strip()
    return Path(env).expanduser().resolve() if env else SHIPPED_DATA


def data_path(*parts: str) -> Path:
    """``data_root() / parts...`` as an absolute path (not checked for existence: readers name
    a missing file in their own error)."""
    return data_root().joinpath(*parts)


def _resolve(relative: str = "") -> str:
    return str(data_path(relative) if relative else data_root())


def register_resolver() -> None:
    """Register ``${occbench.data:...}`` with OmegaConf (idempotent)."""
    if not OmegaConf.has_resolver(RESOLVER):
        OmegaConf.register_new_resolver(RESOLVER, _resolve)


#: Keys of a dataset config that name files or folders, relative to the current directory.
PATH_KEYS = ("root", "path", "gt", "det", "xml", "video", "gt_path")


def absolute_paths(node) -> int:
    """Make every relative file path of a dataset config node (``PATH_KEYS``, at any depth)
    absolute against the current directory, in place, so that a run folder's config.yaml
    names its data from anywhere (``occbench report RUN``). Interpolations (the
    ``occbench.data`` resolver's paths are absolute) and absolute paths are left as they are.
    Returns how many were changed."""
    changed = 0
    if isinstance(node, DictConfig):
        for key in list(node.keys()):
            if OmegaConf.is_interpolation(node, key) or OmegaConf.is_missing(node, key):
                continue
            value = node[key]
            if key in PATH_KEYS and isinstance(value, str) and value:
                full = os.path.abspath(os.path.expanduser(value))
                if full != value:
                    with open_dict(node):
                        node[key] = full
                    changed += 1
            elif isinstance(value, (DictConfig, ListConfig)):
                changed += absolute_paths(value)
    elif isinstance(node, ListConfig):
        for item in node:
            changed += absolute_paths(item)
    return changed
