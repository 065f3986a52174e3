"""Plausibility limits for motion data: what a human motion clip can be, so absurd files are refused at load.

A frame rate of 1e9 or 1e-6, a 1-frame clip, or a translation of 1e12 m is not a motion but a broken file; left
through, they crash the resampler, allocate tens of GiB, or produce clips the sampling kernel cannot interpolate.
Every check raises ``MotionDataError`` naming the file (or ``ConfigError`` for a bad argument).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from refpo_warp.utils.errors import ConfigError, MotionDataError

SOURCE_FPS = (1.0, 2000.0)  # capture rates (AMASS: 60 to 250 Hz)
LIBRARY_FPS = (1.0, 1000.0)  # the rate clips are converted to
MIN_FRAMES = 2  # interpolation needs two frames, velocities need two frames
MAX_CLIP_SECONDS = 3600.0  # AMASS clips last seconds to minutes
MAX_TRANSLATION_M = 1000.0  # root translation (AMASS: within a capture volume of a few metres)
MAX_ANGLE_RAD = 100.0  # axis-angle components (about 16 turns: beyond it a file is garbage, not a pose)
MAX_POSITION_M = 10_000.0  # body positions in a converted library
MAX_SPEED = 100_000.0  # linear (m/s), angular and joint (rad/s) speeds in a converted library


def resampled_frame_count(num_src: int, src_fps: float, fps: float) -> int:
    """Frames of a clip of ``num_src`` frames at ``src_fps`` resampled to ``fps`` (frame k at k / fps seconds)."""
    return math.floor((num_src - 1) / src_fps * fps + 1e-6) + 1


def check_fps_argument(fps: float, name: str = "fps") -> float:
    """The library frame rate a caller asks for (``--fps``, ``MotionLibrary.load(fps=...)``)."""
    lo, hi = LIBRARY_FPS
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not (lo <= fps <= hi):
        raise ConfigError(f"{name}={fps} is invalid; expected a frame rate in [{lo:g}, {hi:g}] frames per second")
    return float(fps)


def check_source(path: Path, fps: float, key: str, num_frames: int, trans: np.ndarray, angles: np.ndarray) -> None:
    """A source motion file: its capture rate, length and magnitudes (the resampled length: ``sources.py``)."""
    lo, hi = SOURCE_FPS
    if not (lo <= fps <= hi):
        raise MotionDataError(
            f"{path}: {key}={fps:g} is not a plausible capture rate; expected {lo:g} to {hi:g} frames per second"
        )
    if num_frames < MIN_FRAMES:
        count = "zero frames" if num_frames == 0 else f"{num_frames} frame"
        raise MotionDataError(f"{path}: the motion has {count}; at least {MIN_FRAMES} are needed")
    duration = (num_frames - 1) / fps
    if duration > MAX_CLIP_SECONDS:
        raise MotionDataError(
            f"{path}: the motion lasts {duration:.0f} s ({num_frames} frames at {fps:g} fps); "
            f"clips longer than {MAX_CLIP_SECONDS:.0f} s are refused"
        )
    _check_magnitude(path, "trans", trans, MAX_TRANSLATION_M, "m")
    _check_magnitude(path, "pose", angles, MAX_ANGLE_RAD, "rad")


def check_library(path: Path, fps: float, clip_names: list[str], clip_frames: np.ndarray, frames: dict) -> None:
    """A converted library file: its frame rate, clip lengths and the magnitudes of its frame arrays."""
    lo, hi = LIBRARY_FPS
    if not (lo <= fps <= hi):
        raise MotionDataError(f"{path}: metadata fps={fps:g} is outside [{lo:g}, {hi:g}]")
    short = np.flatnonzero(clip_frames < MIN_FRAMES)
    if short.size:
        raise MotionDataError(
            f"{path}: clip '{clip_names[int(short[0])]}' has {int(clip_frames[short[0]])} "
            f"frame(s); at least {MIN_FRAMES} are needed"
        )
    long = np.flatnonzero((clip_frames - 1) / fps > MAX_CLIP_SECONDS)
    if long.size:
        raise MotionDataError(f"{path}: clip '{clip_names[int(long[0])]}' lasts more than {MAX_CLIP_SECONDS:.0f} s")
    _check_magnitude(path, "body_pos", frames["body_pos"], MAX_POSITION_M, "m")
    for key in ("body_vel", "body_angvel", "dof_vel"):
        _check_magnitude(path, key, frames[key], MAX_SPEED, "per second")
    _check_magnitude(path, "dof_pos", frames["dof_pos"], MAX_ANGLE_RAD, "rad")


def _check_magnitude(path: Path, key: str, values: np.ndarray, limit: float, unit: str) -> None:
    if values.size and float(np.max(np.abs(values))) > limit:
        frame = int(np.argwhere(np.abs(values) > limit)[0, 0])
        raise MotionDataError(
            f"{path}: '{key}' holds values beyond {limit:g} {unit} (first at frame {frame}); not a plausible motion"
        )
