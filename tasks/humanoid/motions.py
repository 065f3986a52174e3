"""The tracking env's motion source: the ``motion_file`` option resolved and loaded once per process."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from refpo_warp.motion.motion_library import MotionLibrary
from refpo_warp.tasks.humanoid.model import CONTROL_HZ
from refpo_warp.utils.errors import unknown

SHIPPED_MOTIONS = Path(__file__).resolve().parent / "data" / "synthetic"
SHIPPED = "shipped:"  # motion_file=shipped:<file>: one shipped clip, found wherever the package is installed
LIBRARY_FPS = CONTROL_HZ  # AMASS input is converted at the control rate


def resolve_motion_file(motion_file: str) -> Path:
    """``""`` selects every shipped synthetic clip, ``shipped:<file>`` one of them (a file name in
    ``SHIPPED_MOTIONS``); anything else is a path (``~`` expanded)."""
    if not motion_file:
        return SHIPPED_MOTIONS
    if motion_file.startswith(SHIPPED):
        name = motion_file[len(SHIPPED) :]
        shipped = [path.name for path in SHIPPED_MOTIONS.glob("*.npz")]
        if name not in shipped:
            raise unknown("shipped clip in env.motion_file=shipped:<file>", name, shipped)
        return SHIPPED_MOTIONS / name
    return Path(motion_file).expanduser().resolve()


@lru_cache(maxsize=4)
def _host_data(path: Path) -> dict:
    """The library's host data (``MotionLibrary.read``); callers must not modify it."""
    return MotionLibrary.read(path, fps=LIBRARY_FPS)


def load_motions(motion_file: str, device: str) -> MotionLibrary:
    """The motion library of ``motion_file`` on ``device`` (an AMASS folder is converted only once per process)."""
    return MotionLibrary(**_host_data(resolve_motion_file(motion_file)), device=device)


def num_clips(motion_file: str) -> int:
    return len(_host_data(resolve_motion_file(motion_file))["clip_names"])
