"""The converted motion library file (``*.motionlib.npz``): every clip's frames concatenated, per-clip offsets, and
a JSON metadata string; versioned and validated on load.

Arrays (F = total frames, C = clips): ``clip_start (C,)``, ``clip_frames (C,)`` (int64); ``body_pos``,
``body_vel``, ``body_angvel (F, 24, 3)``, ``body_rot (F, 24, 4)`` xyzw, ``dof_pos``, ``dof_vel (F, 69)``
(float32); ``metadata``: JSON with ``format``, ``version``, ``fps``, ``clip_names``, ``body_names``, ``sources``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from refpo_warp.motion.amass import load_npz
from refpo_warp.motion.limits import check_library
from refpo_warp.motion.skeleton import BODY_NAMES, NUM_BODIES, NUM_DOFS
from refpo_warp.utils.atomic_files import atomic_write
from refpo_warp.utils.errors import MotionDataError

LIBRARY_SUFFIX = ".motionlib.npz"
FORMAT_NAME = "refpo_warp.motionlib"
FORMAT_VERSION = 1
# Per-frame arrays and their shape after the frame axis.
FRAME_ARRAYS: dict[str, tuple[int, ...]] = {
    "body_pos": (NUM_BODIES, 3),
    "body_rot": (NUM_BODIES, 4),
    "body_vel": (NUM_BODIES, 3),
    "body_angvel": (NUM_BODIES, 3),
    "dof_pos": (NUM_DOFS,),
    "dof_vel": (NUM_DOFS,),
}


def is_library_file(path: Path) -> bool:
    return path.name.lower().endswith(LIBRARY_SUFFIX)


def save_library(
    path: str | Path,
    frames: dict[str, np.ndarray],
    clip_frames: np.ndarray,
    fps: float,
    clip_names: list[str],
    sources: list[str],
) -> Path:
    """Write a library file atomically (a crash keeps the previous file); ``path`` must end in ``.motionlib.npz``."""
    path = Path(path)
    if not is_library_file(path):
        raise ValueError(f"{path}: a motion library file name must end in '{LIBRARY_SUFFIX}'")
    clip_frames = np.asarray(clip_frames, dtype=np.int64)
    metadata = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "fps": float(fps),
        "clip_names": list(clip_names),
        "body_names": list(BODY_NAMES),
        "sources": list(sources),
    }
    arrays: dict[str, Any] = {key: np.asarray(frames[key], dtype=np.float32) for key in FRAME_ARRAYS}
    arrays["clip_frames"] = clip_frames
    arrays["clip_start"] = np.concatenate([[0], np.cumsum(clip_frames)[:-1]]).astype(np.int64)
    arrays["metadata"] = np.array(json.dumps(metadata))
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as f:  # a file object also keeps numpy from appending a second '.npz'
        np.savez_compressed(f, **arrays)
    return path


def load_library(path: str | Path) -> tuple[dict[str, np.ndarray], np.ndarray, dict]:
    """Read and validate a library file: (frame arrays, clip_frames (C,), metadata)."""
    path = Path(path)
    wanted = {*FRAME_ARRAYS, "clip_start", "clip_frames", "metadata"}
    keys, arrays = load_npz(path, wanted)
    missing = sorted(wanted - keys)
    if missing:
        raise MotionDataError(f"{path}: not a motion library file: missing key(s) {missing}")
    meta = _metadata(path, arrays["metadata"])
    clip_frames, clip_start = arrays["clip_frames"], arrays["clip_start"]
    num_clips = len(meta["clip_names"])
    for key, value in (("clip_frames", clip_frames), ("clip_start", clip_start)):
        if value.shape != (num_clips,) or not np.issubdtype(value.dtype, np.integer):
            raise MotionDataError(
                f"{path}: '{key}' must be {num_clips} integers (one per clip), got {value.dtype} {value.shape}"
            )
    if num_clips == 0:
        raise MotionDataError(f"{path}: the library holds no clips")
    if np.any(clip_frames < 1):
        raise MotionDataError(f"{path}: clip '{meta['clip_names'][int(np.argmin(clip_frames))]}' has zero frames")
    expected_start = np.concatenate([[0], np.cumsum(clip_frames)[:-1]])
    if not np.array_equal(clip_start, expected_start):
        raise MotionDataError(f"{path}: 'clip_start' does not match the running sum of 'clip_frames'")
    total = int(clip_frames.sum())
    frames = {}
    for key, tail in FRAME_ARRAYS.items():
        value = arrays[key]
        if value.shape != (total, *tail) or not np.issubdtype(value.dtype, np.floating):
            raise MotionDataError(f"{path}: '{key}' has {value.dtype} {value.shape}; expected floats {(total, *tail)}")
        if not np.all(np.isfinite(value)):
            raise MotionDataError(f"{path}: '{key}' has NaN or infinite values")
        frames[key] = value.astype(np.float32)
    norms = np.linalg.norm(frames["body_rot"], axis=-1)
    if np.max(np.abs(norms - 1.0)) > 1e-3:
        raise MotionDataError(f"{path}: 'body_rot' holds quaternions that are not unit length")
    check_library(path, float(meta["fps"]), meta["clip_names"], clip_frames, frames)
    return frames, clip_frames.astype(np.int64), meta


def _metadata(path: Path, raw: np.ndarray) -> dict:
    try:
        meta = json.loads(str(raw.reshape(())))
    except (ValueError, TypeError) as err:
        raise MotionDataError(f"{path}: 'metadata' is not a JSON string ({err})") from err
    if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
        raise MotionDataError(f"{path}: 'metadata' does not describe a '{FORMAT_NAME}' file")
    if meta.get("version") != FORMAT_VERSION:
        raise MotionDataError(
            f"{path}: library format version {meta.get('version')} is not supported (this code reads version "
            f"{FORMAT_VERSION}); convert the AMASS files again with `refpo convert-amass`"
        )
    if meta.get("body_names") != list(BODY_NAMES):
        raise MotionDataError(f"{path}: the library's body list differs from the skeleton's {list(BODY_NAMES)}")
    fps = meta.get("fps")
    if not isinstance(fps, (int, float)) or not np.isfinite(fps) or fps <= 0:
        raise MotionDataError(f"{path}: metadata 'fps' must be a positive number, got {fps!r}")
    names = meta.get("clip_names")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise MotionDataError(f"{path}: metadata 'clip_names' must be a list of strings")
    meta.setdefault("sources", [])
    return meta
