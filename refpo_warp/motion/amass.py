"""Read and write AMASS motion files (npz) in both published schemas, with validation.

- SMPL+H (``*_poses.npz``): ``poses (N, 156)`` = root orientation (3), 21 body joints (63), 30 hand joints (90);
  ``trans (N, 3)``, ``mocap_framerate``, ``betas``, ``gender``, ``dmpls (N, 8)``.
- SMPL-X stage-ii (``*_stageii.npz``): ``root_orient (N, 3)``, ``pose_body (N, 63)``, ``pose_hand``, ``pose_jaw``,
  ``pose_eye``, ``poses (N, 165)``, ``trans``, ``mocap_frame_rate``, ``betas``, ``gender``, ...
Only the root orientation, the 21 body joints, the translation and the frame rate are used (hands, face and body
shape are dropped: the skeleton is the SMPL neutral mean shape). Every problem raises ``MotionDataError`` naming
the file, before any of the file is used; implausible rates, lengths and magnitudes too (``motion/limits.py``).
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from refpo_warp.motion.limits import check_source
from refpo_warp.utils.atomic_files import atomic_write
from refpo_warp.utils.errors import MotionDataError

NUM_BODY_POSE = 63  # 21 body joints x 3 (axis-angle), after the 3 root values
SMPLH_POSE_DIM = 156
SMPLX_POSE_DIM = 165
_FPS_KEYS = ("mocap_framerate", "mocap_frame_rate")  # SMPL+H spelling, SMPL-X spelling
# Per-subject files in AMASS folders that hold body shape, not motion: skipped when reading a folder.
METADATA_FILE_NAMES = ("shape.npz",)
METADATA_FILE_SUFFIXES = ("_stagei.npz",)
_USED_KEYS = {"poses", "root_orient", "pose_body", "trans", *_FPS_KEYS}


@dataclass
class AmassMotion:
    """The parts of an AMASS file the motion library uses (axis-angle in SMPL's y-up template frame)."""

    path: Path
    schema: str  # "smplh" or "smplx"
    fps: float
    root_orient: np.ndarray  # (N, 3)
    body_pose: np.ndarray  # (N, 63) SMPL joints 1..21
    trans: np.ndarray  # (N, 3) z-up world, metres

    @property
    def num_frames(self) -> int:
        return self.trans.shape[0]


def is_metadata_file(path: Path) -> bool:
    """True for AMASS body-shape files (``shape.npz``, ``*_stagei.npz``) that carry no motion."""
    name = path.name.lower()
    return name in METADATA_FILE_NAMES or name.endswith(METADATA_FILE_SUFFIXES)


def read_amass(path: str | Path) -> AmassMotion:
    """Read and validate one AMASS npz file of either schema."""
    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise MotionDataError(f"{path}: not an .npz file (expected an AMASS *_poses.npz or *_stageii.npz)")
    keys, arrays = load_npz(path, _USED_KEYS)

    if {"root_orient", "pose_body"} <= keys:
        schema = "smplx"
        root_orient = _matrix(path, arrays, "root_orient", 3)
        body_pose = _matrix(path, arrays, "pose_body", NUM_BODY_POSE)
    elif "poses" in keys:
        schema = "smplh"
        poses = _matrix(path, arrays, "poses", None)
        if poses.shape[1] < 3 + NUM_BODY_POSE:
            raise MotionDataError(
                f"{path}: key 'poses' has shape {poses.shape}; expected (N, {SMPLH_POSE_DIM}) (SMPL+H) or "
                f"(N, {SMPLX_POSE_DIM}) (SMPL-X), at least root + 21 body joints = 66 columns"
            )
        root_orient, body_pose = poses[:, :3], poses[:, 3 : 3 + NUM_BODY_POSE]
    else:
        raise MotionDataError(
            f"{path}: missing key 'poses' (SMPL+H schema) or 'root_orient' + 'pose_body' (SMPL-X stage-ii schema); "
            f"found keys {sorted(keys)}"
        )
    trans = _matrix(path, arrays, "trans", 3)
    if not (root_orient.shape[0] == body_pose.shape[0] == trans.shape[0]):
        raise MotionDataError(
            f"{path}: frame counts differ: pose has {root_orient.shape[0]} frames, 'trans' has {trans.shape[0]}"
        )
    fps, fps_key = _frame_rate(path, arrays, keys)
    check_source(path, fps, fps_key, trans.shape[0], trans, np.concatenate([root_orient, body_pose], axis=1))
    return AmassMotion(path, schema, fps, root_orient, body_pose, trans)


def load_npz(path: Path, wanted: set[str]) -> tuple[set[str], dict[str, np.ndarray]]:
    """All key names of an npz archive and the arrays of the ``wanted`` keys; MotionDataError if unreadable."""
    if not path.is_file():
        raise MotionDataError(f"{path}: no such file")
    try:
        data = np.load(path, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError("it holds a single array, not named arrays")
        with data:
            return set(data.files), {key: data[key] for key in data.files if key in wanted}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
        raise MotionDataError(f"{path}: cannot be read as an npz archive ({err})") from err


def _matrix(path: Path, arrays: dict, key: str, width: int | None) -> np.ndarray:
    if key not in arrays:
        raise MotionDataError(f"{path}: missing key '{key}'")
    value = arrays[key]
    if not np.issubdtype(value.dtype, np.number):
        raise MotionDataError(f"{path}: key '{key}' has dtype {value.dtype}; expected numbers")
    if value.ndim != 2 or (width is not None and value.shape[1] != width):
        expected = f"(N, {width})" if width is not None else "(N, D)"
        raise MotionDataError(f"{path}: key '{key}' has shape {value.shape}; expected {expected}")
    value = value.astype(np.float64)
    bad = ~np.isfinite(value)
    if bad.any():
        frame = int(np.argwhere(bad)[0, 0])
        raise MotionDataError(f"{path}: key '{key}' has NaN or infinite values (first at frame {frame})")
    return value


def _frame_rate(path: Path, arrays: dict, keys: set) -> tuple[float, str]:
    key = next((k for k in _FPS_KEYS if k in keys), None)
    if key is None:
        raise MotionDataError(f"{path}: missing frame rate key ('mocap_framerate' or 'mocap_frame_rate')")
    value = arrays[key]
    if value.size != 1 or not np.issubdtype(value.dtype, np.number):
        raise MotionDataError(f"{path}: key '{key}' must be one number, got {value!r}")
    fps = float(value.reshape(()))
    if not np.isfinite(fps) or fps <= 0.0:
        raise MotionDataError(f"{path}: key '{key}' must be a positive frame rate, got {fps}")
    return fps, key


def write_amass(
    path: str | Path,
    root_orient: np.ndarray,
    body_pose: np.ndarray,
    trans: np.ndarray,
    fps: float,
    schema: str = "smplh",
    gender: str = "neutral",
    dtype: type = np.float64,
) -> Path:
    """Write an AMASS file with zero hands (and zero face / DMPLs / betas); returns the path written.

    ``schema`` is "smplh" (``poses (N, 156)``, ``mocap_framerate``) or "smplx" (stage-ii keys and
    ``poses (N, 165)``, ``mocap_frame_rate``).
    """
    path = Path(path)
    num_frames = trans.shape[0]

    def zeros(*shape: int) -> np.ndarray:
        return np.zeros(shape, dtype=dtype)

    root_orient, body_pose, trans = (np.asarray(a, dtype=dtype) for a in (root_orient, body_pose, trans))
    common: dict[str, Any] = {"trans": trans, "gender": np.array(gender), "betas": zeros(16)}
    if schema == "smplh":
        poses = np.concatenate([root_orient, body_pose, zeros(num_frames, SMPLH_POSE_DIM - 66)], axis=1)
        arrays = {**common, "poses": poses, "mocap_framerate": np.array(float(fps)), "dmpls": zeros(num_frames, 8)}
    elif schema == "smplx":
        jaw, eyes, hands = zeros(num_frames, 3), zeros(num_frames, 6), zeros(num_frames, 90)
        arrays = {
            **common,
            "surface_model_type": np.array("smplx"),
            "mocap_frame_rate": np.array(float(fps)),
            "mocap_time_length": np.array((num_frames - 1) / float(fps)),
            "num_betas": np.array(16),
            "root_orient": root_orient,
            "pose_body": body_pose,
            "pose_hand": hands,
            "pose_jaw": jaw,
            "pose_eye": eyes,
            "poses": np.concatenate([root_orient, body_pose, jaw, eyes, hands], axis=1),
        }
    else:
        raise ValueError(f"Unknown AMASS schema '{schema}': expected 'smplh' or 'smplx'")
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as f:  # a file object also keeps numpy from appending a second '.npz'
        np.savez_compressed(f, **arrays)
    return path
