"""The motion library: many clips at one frame rate, concatenated in Warp arrays with per-clip offsets, and a
graph-capturable kernel that samples each env's reference state at (clip, time) with interpolation.

Frames are in the simulator's z-up world, bodies in skeleton order; body 0 (Pelvis) is the root. ``dof_pos``
holds the 23 non-root joints' local rotations as intrinsic x-y-z Euler angles (the humanoid's three hinges per
joint, x then y then z); ``dof_vel`` their rates. See ``docs/motion.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from refpo_warp.motion.clip import MotionClip
from refpo_warp.motion.library_file import FRAME_ARRAYS, is_library_file, load_library, save_library
from refpo_warp.motion.limits import check_fps_argument
from refpo_warp.motion.skeleton import NUM_BODIES, NUM_DOFS
from refpo_warp.motion.sources import load_amass_clips
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.errors import MotionDataError
from refpo_warp.utils.warp_setup import init_warp, wp

_WARP_DTYPES = {
    "body_pos": wp.vec3,
    "body_rot": wp.quat,
    "body_vel": wp.vec3,
    "body_angvel": wp.vec3,
    "dof_pos": float,
    "dof_vel": float,
}


@wp.struct
class MotionFrames:
    """Reference states, one row per env (written by ``MotionLibrary.sample``) or per frame (the library's own
    ``frames_device``): one argument of every kernel that reads or writes them."""

    body_pos: wp.array2d(dtype=wp.vec3)  # (rows, 24)
    body_rot: wp.array2d(dtype=wp.quat)  # (rows, 24) xyzw
    body_vel: wp.array2d(dtype=wp.vec3)  # (rows, 24)
    body_angvel: wp.array2d(dtype=wp.vec3)  # (rows, 24)
    dof_pos: wp.array2d(dtype=float)  # (rows, 69)
    dof_vel: wp.array2d(dtype=float)  # (rows, 69)


class MotionLibrary:
    """Clips concatenated on a Warp device; build with ``load`` (or ``from_clips``)."""

    def __init__(
        self,
        frames: dict[str, np.ndarray],
        clip_frames: np.ndarray,
        fps: float,
        clip_names: list[str],
        sources: list[str] | None = None,
        device: str = "cpu",
    ) -> None:
        init_warp()
        self.device = resolve_device(device)
        self.fps = float(fps)
        self.clip_names = list(clip_names)
        self.num_clips = len(self.clip_names)
        self.sources = list(sources or [])
        self.clip_num_frames = np.asarray(clip_frames, dtype=np.int64)
        if self.num_clips < 1 or self.clip_num_frames.shape != (self.num_clips,) or self.clip_num_frames.min() < 1:
            raise ValueError(
                f"MotionLibrary needs at least one clip and one frame count >= 1 per clip, got "
                f"{self.num_clips} clip names and frame counts {self.clip_num_frames.tolist()[:8]}"
            )
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"MotionLibrary: fps must be a positive number, got {fps}")
        self.clip_duration = (self.clip_num_frames - 1) / self.fps
        self.num_frames = int(self.clip_num_frames.sum())
        self.frames = {key: np.ascontiguousarray(frames[key], dtype=np.float32) for key in FRAME_ARRAYS}
        start = np.concatenate([[0], np.cumsum(self.clip_num_frames)[:-1]])
        dev = self.device
        self.clip_start: wp.array = wp.array(start.astype(np.int32), dtype=int, device=dev)
        self.clip_frames: wp.array = wp.array(self.clip_num_frames.astype(np.int32), dtype=int, device=dev)
        self.clip_duration_device: wp.array = wp.array(self.clip_duration.astype(np.float32), dtype=float, device=dev)
        self.frames_device = MotionFrames()
        for key, dtype in _WARP_DTYPES.items():
            setattr(self.frames_device, key, wp.array(self.frames[key], dtype=dtype, device=dev))

    # ------------------------------------------------------------------------------------------------ building
    @classmethod
    def load(cls, source: str | Path, device: str = "cpu", fps: float = 30.0) -> MotionLibrary:
        """Load an AMASS npz file, a folder of them (recursive), or a converted library file (*.motionlib.npz).

        AMASS input is converted on the fly at ``fps``; a library file keeps the frame rate it was converted at
        (``sample`` interpolates at any time, so any control rate can use it). Raises ``MotionDataError`` naming
        the file and the problem; nothing is built from a partly read source.
        """
        return cls(**cls.read(source, fps), device=device)

    @staticmethod
    def read(source: str | Path, fps: float = 30.0) -> dict:
        """The host data ``load`` builds a library from (the constructor's arguments but ``device``), for callers
        that keep it to build libraries on several devices without reading or converting the source again."""
        path = Path(source).expanduser()
        if not path.exists():
            raise MotionDataError(
                f"{path}: motion source not found (expected an AMASS .npz file, a folder of "
                f"them, or a *.motionlib.npz library)"
            )
        if path.is_file() and is_library_file(path):
            frames, clip_frames, meta = load_library(path)
            return {
                "frames": frames,
                "clip_frames": clip_frames,
                "fps": meta["fps"],
                "clip_names": meta["clip_names"],
                "sources": meta["sources"],
            }
        clips, sources = load_amass_clips(path, check_fps_argument(fps))
        return _concatenate(clips, sources)

    @classmethod
    def from_clips(cls, clips: list[MotionClip], device: str = "cpu", sources: list[str] | None = None):
        """Concatenate clips that share one frame rate."""
        return cls(**_concatenate(clips, sources), device=device)

    def save(self, path: str | Path) -> None:
        """Write the converted library file (``*.motionlib.npz``)."""
        save_library(path, self.frames, self.clip_num_frames, self.fps, self.clip_names, self.sources)

    def clip(self, index: int) -> dict[str, np.ndarray]:
        """Host copies of one clip's frame arrays (for tools and tests)."""
        start = int(np.sum(self.clip_num_frames[:index]))
        stop = start + int(self.clip_num_frames[index])
        return {key: value[start:stop] for key, value in self.frames.items()}

    # ------------------------------------------------------------------------------------------------ sampling
    def allocate_frames(self, num_envs: int) -> MotionFrames:
        """Output buffers for ``sample`` (allocate once, reuse every step)."""
        dev = self.device

        out = MotionFrames()
        for key, dtype in _WARP_DTYPES.items():
            width = NUM_BODIES if key.startswith("body") else NUM_DOFS
            setattr(out, key, wp.zeros((num_envs, width), dtype=dtype, device=dev))
        return out

    def sample(self, clip_ids: wp.array, times: wp.array, out: MotionFrames, mask: wp.array | None = None) -> None:
        """Reference states at ``times`` seconds into each env's clip (one launch over (env, body); no host sync).

        Times are clamped to [0, clip duration] and clip ids to [0, num_clips - 1]. Positions, velocities and
        joint angles are interpolated linearly between the two bracketing frames (angles along the shorter way
        round), rotations by slerp. ``clip_ids`` and ``times`` hold one entry per row of ``out``. With a bool
        ``mask`` (one entry per row) only the rows where it is set are written; the others keep their values.
        """
        num_envs = out.body_pos.shape[0]
        if clip_ids.shape[0] != num_envs or times.shape[0] != num_envs:
            raise ValueError(
                f"MotionLibrary.sample: {clip_ids.shape[0]} clip ids and {times.shape[0]} times for "
                f"{num_envs} output rows; they must match"
            )
        if mask is not None and mask.shape[0] != num_envs:
            raise ValueError(f"MotionLibrary.sample: {mask.shape[0]} mask entries for {num_envs} output rows")
        wp.launch(
            _sample_kernel,
            dim=(num_envs, NUM_BODIES),
            inputs=[
                self.clip_start,
                self.clip_frames,
                self.num_clips,
                self.fps,
                self.frames_device,
                clip_ids,
                times,
                int(mask is not None),
                mask,
            ],
            outputs=[out],
            device=self.device,
        )

    def __repr__(self) -> str:
        return (
            f"MotionLibrary({self.num_clips} clips, {self.num_frames} frames at {self.fps:g} fps, "
            f"{float(self.clip_duration.sum()):.1f} s, device={self.device})"
        )


def _concatenate(clips: list[MotionClip], sources: list[str] | None) -> dict:
    """Constructor arguments (but ``device``) of the library of ``clips``, which must share one frame rate."""
    if not clips:
        raise ValueError("MotionLibrary.from_clips needs at least one clip")
    rates = {clip.fps for clip in clips}
    if len(rates) != 1:
        raise ValueError(f"MotionLibrary.from_clips: clips have different frame rates {sorted(rates)}")
    frames = {key: np.concatenate([getattr(c, key) for c in clips]) for key in FRAME_ARRAYS}
    clip_frames = np.array([c.num_frames for c in clips])
    return {
        "frames": frames,
        "clip_frames": clip_frames,
        "fps": rates.pop(),
        "clip_names": [c.name for c in clips],
        "sources": sources,
    }


@wp.func
def _slerp(q0: wp.quat, q1: wp.quat, a: float) -> wp.quat:
    d = wp.dot(q0, q1)
    q_end = q1
    if d < 0.0:  # q and -q are one rotation: take the shorter arc
        q_end = q1 * -1.0
        d = -d
    if d > 0.9995:  # nearly equal: normalised lerp avoids dividing by sin(theta) ~ 0
        return wp.normalize(q0 * (1.0 - a) + q_end * a)
    theta = wp.acos(d)
    s = wp.sin(theta)
    return wp.normalize(q0 * (wp.sin((1.0 - a) * theta) / s) + q_end * (wp.sin(a * theta) / s))


@wp.func
def _wrap(x: float) -> float:
    return x - 2.0 * wp.pi * wp.floor((x + wp.pi) / (2.0 * wp.pi))


@wp.kernel
def _sample_kernel(
    clip_start: wp.array(dtype=int),
    clip_frames: wp.array(dtype=int),
    num_clips: int,
    fps: float,
    frames: MotionFrames,
    clip_ids: wp.array(dtype=int),
    times: wp.array(dtype=float),
    use_mask: int,
    mask: wp.array(dtype=wp.bool),
    out: MotionFrames,
):
    env, body = wp.tid()
    # Warp kernel code: nested, as `and` is not short-circuit in Warp and mask may be empty when use_mask is 0
    if use_mask != 0:  # noqa: SIM102
        if not mask[env]:
            return
    if num_clips < 1:
        return
    # Every index is clamped into its array: no clip id, time (NaN included) or frame table can read out of bounds.
    clip = wp.clamp(clip_ids[env], 0, num_clips - 1)
    last = wp.max(clip_frames[clip] - 1, 0)
    f = wp.clamp(times[env] * fps, 0.0, float(last))
    k0 = wp.clamp(int(f), 0, last)
    a = wp.clamp(f - float(k0), 0.0, 1.0)
    total = frames.body_pos.shape[0] - 1
    g0 = wp.clamp(clip_start[clip] + k0, 0, total)
    g1 = wp.clamp(clip_start[clip] + wp.min(k0 + 1, last), 0, total)

    out.body_pos[env, body] = wp.lerp(frames.body_pos[g0, body], frames.body_pos[g1, body], a)
    out.body_rot[env, body] = _slerp(frames.body_rot[g0, body], frames.body_rot[g1, body], a)
    out.body_vel[env, body] = wp.lerp(frames.body_vel[g0, body], frames.body_vel[g1, body], a)
    out.body_angvel[env, body] = wp.lerp(frames.body_angvel[g0, body], frames.body_angvel[g1, body], a)
    if body > 0:  # the joint of body b (> 0) owns dofs 3(b-1) .. 3(b-1)+2
        for axis in range(3):
            d = 3 * (body - 1) + axis
            x0 = frames.dof_pos[g0, d]
            out.dof_pos[env, d] = _wrap(x0 + a * _wrap(frames.dof_pos[g1, d] - x0))
            out.dof_vel[env, d] = wp.lerp(frames.dof_vel[g0, d], frames.dof_vel[g1, d], a)
