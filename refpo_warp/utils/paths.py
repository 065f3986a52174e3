"""Where the repository's folders are: its root, ``configs/`` (``REFPO_WARP_CONFIGS`` points elsewhere) and
``tools/`` (the training command a sweep launches)."""

from __future__ import annotations

import os
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
CONFIG_DIR = Path(os.environ.get("REFPO_WARP_CONFIGS", REPO_ROOT / "configs"))
TOOLS_DIR = REPO_ROOT / "tools"
