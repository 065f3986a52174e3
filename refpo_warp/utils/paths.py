"""Where the installed package keeps its files: the shipped configs (the repository's ``configs/``, installed as
``refpo_warp.configs``), found through the package wherever it is installed, and the source tree of a checkout
(the layering checks and the tests read it).

A user's own config folders come on top of the shipped one: ``refpo_warp.config.config_path``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]


def _packaged_config_dir() -> Path:
    # The package data folder itself, not an import of it: find_spec locates it in a wheel and in an editable install.
    spec = importlib.util.find_spec("refpo_warp.configs")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError(
            "refpo_warp's shipped configs (refpo_warp.configs) are not installed beside it: install the "
            "package again (pip install -e . in a checkout; an editable install from before the configs "
            "moved into the package lacks them)"
        )
    return Path(spec.submodule_search_locations[0]).resolve()


PACKAGED_CONFIG_DIR = _packaged_config_dir()
# The checkout the package was installed from in editable mode (in a wheel: the site-packages folder).
REPO_ROOT = PACKAGE_DIR.parent


def shown(path: str | Path) -> str:
    """A file's name as messages show it: ``configs/...`` for a shipped config, relative to the installation for the
    package's own files (``refpo_warp/algorithms/refpo.py``), else the path as it is."""
    path = Path(path).resolve()
    for base, prefix in ((PACKAGED_CONFIG_DIR, Path("configs")), (REPO_ROOT, Path())):
        if path.is_relative_to(base):
            return str(prefix / path.relative_to(base))
    return str(path)
