"""DMC-style control tasks (MuJoCo Playground's DM Control Suite) on Newton's MuJoCo solver, one world per env.

One control step: squash actions with tanh (``action_transform``; or clip them) into the MuJoCo actuator controls,
run the task's physics substeps, compute the reward from the new state and end the episodes whose physics state is
no longer finite (terminated, reward 0, counted in the ``nonfinite_resets`` episode metric). The base env then applies
the time-out after ``max_episode_length`` steps (truncated, so the value is bootstrapped) and the task re-initialises
the finished envs and writes every observation. Everything runs in Warp kernels over the env index and is replayed
as one captured graph after the first step.
"""

from __future__ import annotations

import torch

from refpo_warp.envs.warp_vec_env import WarpVecEnv
from refpo_warp.sim import MuJoCoWorlds, world_state_finite
from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.dmc.cfg import DmcCfg, task_cfg_class
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.warp_setup import wp


@wp.kernel
def apply_actions(actions: wp.array2d(dtype=float), ctrl: wp.array2d(dtype=float)):
    i, j = wp.tid()
    ctrl[i, j] = wp.clamp(actions[i, j], -1.0, 1.0)


@wp.kernel
def end_diverged_worlds(
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    rewards: wp.array(dtype=float),
    terminated: wp.array(dtype=wp.bool),
    nonfinite_resets: wp.array(dtype=float),
):
    i = wp.tid()
    finite = world_state_finite(joint_q, joint_qd, i)
    if not finite:
        rewards[i] = 0.0  # the reward of a diverged state is meaningless (and may be NaN)
    terminated[i] = not finite
    nonfinite_resets[i] = wp.where(finite, 0.0, 1.0)


class DmcEnv(WarpVecEnv):
    """A DMC task (``cfg.task``) over ``num_envs`` Newton worlds; see the module docstring for the step."""

    cfg: DmcCfg
    cfg_class = DmcCfg
    episode_metrics = ("nonfinite_resets",)
    supports_final_observations = True

    def _spaces(self):
        if self.cfg.task not in suite.task_names():
            raise unknown("DMC task (env.task)", self.cfg.task, suite.task_names())
        if not isinstance(self.cfg, own := task_cfg_class(self.cfg.task)):  # a spec registered with another cfg
            raise ConfigError(f"DMC task {self.cfg.task} takes a {own.__name__}, got a {type(self.cfg).__name__}")
        self.task_class = suite.task_class(self.cfg.task)
        self.episode_metrics = DmcEnv.episode_metrics + self.task_class.episode_metrics
        self.curve_metrics = self.task_class.episode_metrics
        return self.task_class.num_actions, {"policy": self.task_class.num_obs}

    def _build(self) -> None:
        cfg, task_class = self.cfg, self.task_class
        options = {}
        if cfg.solver_iterations:
            options["iterations"] = cfg.solver_iterations
        if cfg.solver_ls_iterations:
            options["ls_iterations"] = cfg.solver_ls_iterations
        # warn_overflow off: MuJoCo Warp would print a line per step when the models' (deliberately low, Playground's)
        # iteration caps are hit.
        self.sim = MuJoCoWorlds(
            task_class.model_path(), self.num_envs, self.device, task_class.substeps, options, warn_overflow=False
        )
        ctrl = self.sim.views.ctrl
        if ctrl is None or ctrl.shape[1] != task_class.num_actions:
            raise ValueError(
                f"{task_class.model_file}: expected {task_class.num_actions} actuators, found "
                f"{0 if ctrl is None else ctrl.shape[1]}"
            )
        self.task = task_class(self.sim, cfg, self.buffers.rng)
        self.task.prepare()
        self._no_resets = wp.zeros(self.num_envs, dtype=wp.bool)  # observe() mask for the pre-reset observation

    def _step_impl(self) -> None:
        b, sim, task = self.buffers, self.sim, self.task
        wp.launch(apply_actions, dim=(self.num_envs, self.num_actions), inputs=[b.actions, sim.views.ctrl])
        sim.simulate()
        task.after_physics()
        task.reward(b.rewards)
        task.record_metrics(b.metrics)
        wp.launch(
            end_diverged_worlds,
            dim=self.num_envs,
            inputs=[sim.views.joint_q, sim.views.joint_qd, b.rewards, b.terminated, b.metrics["nonfinite_resets"]],
        )

    def _observe_final(self) -> None:
        self.task.observe(self.buffers.final_obs["policy"], self._no_resets)

    def _reset_impl(self, mask) -> None:
        """Initial states of the envs in ``mask``, then the observations of all envs."""
        self.task.reset(mask)
        self.sim.after_reset(mask)
        self.task.observe(self.buffers.obs["policy"], mask)

    @property
    def step_dt(self) -> float:
        """Control period in seconds (physics timestep x substeps)."""
        return self.sim.control_dt

    @property
    def joint_q(self) -> torch.Tensor:
        """Generalized positions per env, shape (num_envs, coords), Newton convention (MuJoCo qpos - ref); live."""
        return wp.to_torch(self.sim.views.joint_q)

    @property
    def joint_qd(self) -> torch.Tensor:
        """Generalized velocities per env, shape (num_envs, dofs); a live view."""
        return wp.to_torch(self.sim.views.joint_qd)

    def set_state(self, qpos: torch.Tensor, qvel: torch.Tensor) -> None:
        """Put every env in a MuJoCo state (``qpos`` as MuJoCo stores it, joint ``ref`` included; ``qvel``) and
        recompute its observations; episode counters are kept (tests, figures, MuJoCo C comparisons)."""
        v = self.sim.views
        qpos = torch.as_tensor(qpos, dtype=torch.float32, device=self.device).reshape(v.joint_q.shape)
        qvel = torch.as_tensor(qvel, dtype=torch.float32, device=self.device).reshape(v.joint_qd.shape)
        self.joint_q.copy_(qpos - self._coord_ref())
        self.joint_qd.copy_(qvel)
        with wp.ScopedDevice(self.wp_device):
            self.sim.reset_mask.fill_(True)
            self.sim.after_reset()
            self.task.observe(self.buffers.obs["policy"], self.sim.reset_mask)
            self.sim.reset_mask.zero_()

    @property
    def qpos(self) -> torch.Tensor:
        """MuJoCo generalized positions per env (joint ``ref`` included), shape (num_envs, nq); a copy."""
        return self.joint_q + self._coord_ref()

    def _coord_ref(self) -> torch.Tensor:
        """The MJCF joint ``ref`` per coordinate (MuJoCo qpos = joint_q + ref), which a model without free or ball
        joints has (every DMC task's)."""
        ref = self.sim.views.coord_ref
        if ref is None:
            raise ValueError(f"{self.cfg.task}: a model with free or ball joints has no per-coordinate qpos")
        return wp.to_torch(ref)

    def compute_rewards(self, actions: torch.Tensor) -> torch.Tensor:
        """Rewards of the current states under ``actions`` (transformed as in a step), without stepping.

        Contact-based inputs (finger touch) keep their last values; use after ``set_state`` (tests, figures).
        """
        out = torch.zeros(self.num_envs, device=self.device)
        actions = actions.to(self.device, torch.float32).reshape(self.num_envs, self.num_actions).contiguous()
        with wp.ScopedDevice(self.wp_device):
            wp_actions = wp.from_torch(actions.clone())
            self.transform_actions(wp_actions)
            wp.launch(apply_actions, dim=(self.num_envs, self.num_actions), inputs=[wp_actions, self.sim.views.ctrl])
            self.task.reward(wp.from_torch(out))
        return out
