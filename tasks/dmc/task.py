"""What one DMC task adds to the shared Newton env: its model file, sizes, and reset/reward/observation kernels.

A task is a module of ``tasks/dmc/suite/`` that defines one subclass (the module's name is the task's name). The
subclass sets the class attributes and launches its kernels over the env (= world) index; its reset kernel is
``reset_kernel`` of a ``wp.func`` that draws one env's initial state. Kernels read the
simulation through ``self.views`` (per-world views of joint coordinates, body poses, controls; see
``refpo_warp.sim.WorldViews``) and write only the arrays they are given. All launches must be graph-capturable.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from refpo_warp.sim import MuJoCoWorlds
from refpo_warp.utils.warp_setup import wp

MODELS_DIR = Path(__file__).resolve().parent / "models"


def reset_kernel(draw: Callable[..., Any], params_type) -> wp.Kernel:
    """The reset kernel of a task: in each env i where ``mask[i]`` is set, ``draw(i, state, params, joint_q,
    joint_qd) -> state`` writes the initial joint coordinates and velocities (and any task state that ``params``
    holds), drawing from env i's random stream ``state``, and returns the advanced stream. ``params`` is one
    argument of Warp type ``params_type`` (a ``wp.struct`` for several)."""
    # Warp types @wp.func as returning the decorated Python function; the object it returns is a wp.Function.
    assert isinstance(draw, wp.Function) and draw.func is not None

    def reset(
        mask: wp.array(dtype=wp.bool),
        rng: wp.array(dtype=wp.uint32),
        params: object,
        joint_q: wp.array2d(dtype=float),
        joint_qd: wp.array2d(dtype=float),
    ):
        i = wp.tid()
        if mask[i]:
            rng[i] = draw(i, rng[i], params, joint_q, joint_qd)

    # Set here: a (postponed) string annotation cannot name the closure's argument.
    reset.__annotations__["params"] = params_type
    # In the Warp module of ``draw`` (the task's): building one task's kernel leaves the others' modules as they are.
    return wp.Kernel(reset, key=f"reset_{draw.func.__name__}", module=draw.module)


@wp.struct
class UniformRanges:
    lower: wp.array(dtype=float)
    upper: wp.array(dtype=float)


@wp.func
def draw_uniform(
    i: int, state: wp.uint32, ranges: UniformRanges, joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float)
) -> wp.uint32:
    """Joint coordinate j ~ U(lower[j], upper[j]) (exactly lower[j] where the two are equal), zero velocities."""
    s = state
    for j in range(joint_q.shape[1]):
        joint_q[i, j] = wp.randf(s, ranges.lower[j], ranges.upper[j])
        joint_qd[i, j] = 0.0
    return s


reset_uniform = reset_kernel(draw_uniform, UniformRanges)


class DmcTask:
    """Base class of the DMC tasks (one instance per env, built after the simulation)."""

    model_file: ClassVar[str]  # file in tasks/dmc/models/
    substeps: ClassVar[int]  # physics steps per control step (Playground ctrl_dt / sim_dt)
    num_obs: ClassVar[int]
    num_actions: ClassVar[int]
    # One line each in docs/dmc.md's task table (tasks/dmc/doc_tables.py); the module docstring states them exactly.
    reward_summary: ClassVar[str]
    reset_summary: ClassVar[str]
    render_camera: ClassVar[str] = "fixed"  # refpo_warp/render: "fixed", "track" (track_body) or a camera of the file
    track_body: ClassVar[str | None] = None
    render_view: ClassVar[tuple[float, float]] = (-20.0, 90.0)  # camera elevation, azimuth (deg): the x-z plane
    render_distance: ClassVar[float | None] = None  # of the camera; None: from the size of the model's geoms
    # Per-episode metrics the task writes (``record_metrics``) beside the env's; read where an episode ends: logged as
    # ``Episode/<name>``, averaged in ``eval.json`` (``<name>_mean``) and the periodic evaluation (``eval/<name>_N10``).
    episode_metrics: ClassVar[tuple[str, ...]] = ()

    def __init__(self, sim: MuJoCoWorlds, cfg, rng) -> None:
        self.sim = sim
        self.views = sim.views
        self.cfg = cfg
        self.rng = rng  # per-env uint32 random streams, advanced in place
        self.num_envs = sim.num_worlds
        self.device = sim.model.device

    @classmethod
    def model_path(cls) -> Path:
        return MODELS_DIR / cls.model_file

    def launch(self, kernel, inputs) -> None:
        wp.launch(kernel, dim=self.num_envs, inputs=inputs, device=self.device)

    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the joint limits (Newton coordinates, i.e. qpos - ref), to edit into reset ranges."""
        return self.views.limit_lower.copy(), self.views.limit_upper.copy()

    def uniform_ranges(self, lower, upper) -> UniformRanges:
        """Per-joint reset ranges for ``reset_uniform_joints`` (one entry per joint coordinate)."""
        ranges = UniformRanges()
        ranges.lower = wp.array(np.asarray(lower, dtype=np.float32), dtype=float, device=self.device)
        ranges.upper = wp.array(np.asarray(upper, dtype=np.float32), dtype=float, device=self.device)
        return ranges

    def launch_reset(self, kernel: wp.Kernel, mask, params) -> None:
        """Launch a kernel of ``reset_kernel`` on the masked envs with the task's ``params``."""
        v = self.views
        self.launch(kernel, [mask, self.rng, params, v.joint_q, v.joint_qd])

    def reset_uniform_joints(self, mask, ranges: UniformRanges) -> None:
        """Draw every joint coordinate of the masked envs uniformly in ``ranges``; zero their velocities."""
        self.launch_reset(reset_uniform, mask, ranges)

    # ------------------------------------------------------------------------------------------ task contract
    def prepare(self) -> None:
        """One-time work after the simulation exists and before the first reset (e.g. a bank of settled states)."""

    def reset(self, mask) -> None:
        """Write initial joint coordinates/velocities (and task state) of the envs where ``mask`` is true."""
        raise NotImplementedError

    def after_physics(self) -> None:
        """Read solver outputs that the reward or observation needs (e.g. contact forces), after ``simulate``."""

    def reward(self, rewards) -> None:
        """Write this control step's reward of every env (from the post-physics state and clipped controls)."""
        raise NotImplementedError

    def observe(self, obs, reset_mask) -> None:
        """Write the observation of every env; ``reset_mask`` marks envs whose state was just re-initialised."""
        raise NotImplementedError

    def record_metrics(self, metrics: dict) -> None:
        """Write this step's value of each of ``episode_metrics`` into ``metrics[name]`` (a per-env Warp array); the
        value after an episode's last step is the episode's."""

    def render_mocap(self, i: int) -> np.ndarray | None:
        """Env i's mocap body positions (nmocap, 3) for its frames, where the task keeps per-env state that the file
        shows as a mocap body (a target); None: the file's."""
        return None
