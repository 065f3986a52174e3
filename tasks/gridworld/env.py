"""GridWorld as Warp kernels over the env index.

Dynamics (paper Appendix B.1, reference ``two_walls`` mode): integer position (x, y) on a size x size grid; the
continuous 2-D action is clipped to [-1, 1] and rounded per axis to {-1, 0, 1} (|a| > 0.5 moves; diagonals allowed);
the position is clipped to the grid. Rows y in {0, 1} (bottom) and {size-2, size-1} (top) are goals: reward
``goal_reward`` and the episode ends (terminated). Otherwise the reward is 0 and the base env's time-out ends the
episode after ``max_episode_length`` steps. Resets are uniform over the non-goal cells. Observation: (pos - c) / c,
c = (size-1)/2.
"""

from __future__ import annotations

import torch

from refpo_warp.envs.episode import finish_env_step
from refpo_warp.envs.warp_vec_env import WarpVecEnv
from refpo_warp.tasks.gridworld.cfg import GridWorldCfg
from refpo_warp.utils.warp_setup import wp


@wp.func
def move(a: float) -> int:
    # np.round(np.clip(a, -1, 1)): ties at +-0.5 round to even (0), so only |a| > 0.5 moves.
    if a > 0.5:
        return 1
    if a < -0.5:
        return -1
    return 0


@wp.func
def is_goal_row(y: int, size: int) -> bool:
    return y <= 1 or y >= size - 2


@wp.func
def write_obs(obs: wp.array2d(dtype=float), i: int, p: wp.vec2i, size: int):
    c = float(size - 1) * 0.5
    obs[i, 0] = (float(p[0]) - c) / c
    obs[i, 1] = (float(p[1]) - c) / c


@wp.func
def sample_start(rng: wp.array(dtype=wp.uint32), i: int, size: int) -> wp.vec2i:
    state = rng[i]
    x = wp.randi(state, 0, size)
    y = wp.randi(state, 2, size - 2)
    rng[i] = state
    return wp.vec2i(x, y)


@wp.kernel
def step_kernel(
    actions: wp.array2d(dtype=float),
    pos: wp.array(dtype=wp.vec2i),
    rng: wp.array(dtype=wp.uint32),
    size: int,
    goal_reward: float,
    max_episode_length: int,
    episode_length: wp.array(dtype=wp.int32),
    obs: wp.array2d(dtype=float),
    rewards: wp.array(dtype=float),
    terminated: wp.array(dtype=wp.bool),
    truncated: wp.array(dtype=wp.bool),
    done: wp.array(dtype=wp.bool),
    success: wp.array(dtype=float),
    reached_top: wp.array(dtype=float),
    final_obs: wp.array2d(dtype=float),
):
    """The whole step of one env (``step_finishes_episode``): move, reward, the base's episode rule, auto-reset."""
    i = wp.tid()
    p = pos[i]
    dx = move(wp.clamp(actions[i, 0], -1.0, 1.0))
    dy = move(wp.clamp(actions[i, 1], -1.0, 1.0))
    p = wp.vec2i(wp.clamp(p[0] + dx, 0, size - 1), wp.clamp(p[1] + dy, 0, size - 1))
    goal = is_goal_row(p[1], size)
    rewards[i] = wp.where(goal, goal_reward, 0.0)
    terminated[i] = goal
    success[i] = wp.where(goal, 1.0, 0.0)
    reached_top[i] = wp.where(goal and p[1] >= size - 2, 1.0, 0.0)
    write_obs(final_obs, i, p, size)  # before any reset (two floats: cheaper to always write than to branch)
    if finish_env_step(i, max_episode_length, 0, terminated, truncated, episode_length, done):
        p = sample_start(rng, i, size)
    pos[i] = p
    write_obs(obs, i, p, size)


@wp.kernel
def reset_kernel(
    mask: wp.array(dtype=wp.bool),
    pos: wp.array(dtype=wp.vec2i),
    rng: wp.array(dtype=wp.uint32),
    size: int,
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    if mask[i]:
        pos[i] = sample_start(rng, i, size)
        write_obs(obs, i, pos[i], size)


class GridWorldEnv(WarpVecEnv):
    """Multimodal GridWorld; ``episode_metrics`` record whether and where (top/bottom) a goal was reached."""

    cfg_class = GridWorldCfg
    cfg: GridWorldCfg
    episode_metrics = ("success", "reached_top")
    supports_final_observations = True
    step_finishes_episode = True  # a few flops per env: one kernel launch instead of three

    def _spaces(self):
        if self.cfg.size < 5:
            raise ValueError(f"GridWorld size must be >= 5 (two goal rows at each end), got {self.cfg.size}")
        return 2, {"policy": 2}

    def _build(self) -> None:
        self._pos = torch.zeros(self.num_envs, 2, dtype=torch.int32, device=self.device)
        self.pos = wp.from_torch(self._pos, dtype=wp.vec2i)

    def _step_impl(self) -> None:
        b, c = self.buffers, self.cfg
        wp.launch(
            step_kernel,
            dim=self.num_envs,
            inputs=[b.actions, self.pos, b.rng, c.size, c.goal_reward, self.max_episode_length, b.episode_length],
            outputs=[
                b.obs["policy"],
                b.rewards,
                b.terminated,
                b.truncated,
                b.done,
                b.metrics["success"],
                b.metrics["reached_top"],
                b.final_obs["policy"],
            ],
        )

    def _reset_impl(self, mask) -> None:
        wp.launch(
            reset_kernel,
            dim=self.num_envs,
            inputs=[mask, self.pos, self.buffers.rng, self.cfg.size],
            outputs=[self.buffers.obs["policy"]],
        )

    @property
    def positions(self) -> torch.Tensor:
        """Current integer (x, y) positions, shape (num_envs, 2) (a live view)."""
        return self._pos

    def reset_to(self, positions: torch.Tensor) -> None:
        """Start a new episode in every env from the given (x, y) cells (used by figures and tests)."""
        positions = torch.as_tensor(positions, dtype=torch.int32, device=self.device).reshape(self.num_envs, 2)
        if (positions < 0).any() or (positions >= self.cfg.size).any():
            raise ValueError(f"positions must lie on the {self.cfg.size}x{self.cfg.size} grid")
        self._pos.copy_(positions)
        self.restart_counters()
        c = (self.cfg.size - 1) / 2
        self._obs["policy"].copy_((positions.float() - c) / c)
