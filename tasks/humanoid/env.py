"""SMPL humanoid motion tracking (ReFPO paper §4.3): a Newton-simulated humanoid follows reference clips.

Per control step (30 Hz), all in Warp kernels and captured as one graph: PD targets from the actions, 4 physics
substeps, the reference at the new time, reward terms / termination / clip-end truncation / episode metrics; then the
base env's episode rules (``refpo_warp/envs/episode.py``), new episodes for finished envs (reference-state
initialisation: the simulator is set to the reference at the episode's start time), and the observation against the
reference one control step ahead. Details: ``docs/humanoid.md``.
"""

from __future__ import annotations

import numpy as np
import torch

from refpo_warp.envs.warp_vec_env import WarpVecEnv
from refpo_warp.motion import skeleton as sk
from refpo_warp.tasks.humanoid import motions
from refpo_warp.tasks.humanoid.cfg import HumanoidTrackingCfg
from refpo_warp.tasks.humanoid.model import CONTROL_HZ, EFFORT_LIMIT, HumanoidSim, SimOptions
from refpo_warp.tasks.humanoid.obs_layout import OBS_DIM, conditioning_mask
from refpo_warp.tasks.humanoid.observations import observation_kernel
from refpo_warp.tasks.humanoid.reward_terms import TERMS, reward_params
from refpo_warp.tasks.humanoid.tracking_kernels import (
    advance_time_kernel,
    apply_actions_kernel,
    reward_and_termination_kernel,
    start_episodes_kernel,
    write_reference_state_kernel,
)
from refpo_warp.utils.warp_setup import wp


class HumanoidTrackingEnv(WarpVecEnv):
    """Motion tracking with 69 PD-controlled hinges; observation groups ``policy`` (masked) and ``critic`` (full)."""

    cfg_class = HumanoidTrackingCfg
    cfg: HumanoidTrackingCfg
    episode_metrics = ("success", "mpjpe_mm", "alive_steps")
    reward_terms = TERMS
    task_truncation = True  # the end of the reference clip

    @classmethod
    def eval_num_envs(cls, cfg: HumanoidTrackingCfg) -> int:
        """Evaluation plays every clip once: one env per clip."""
        return motions.num_clips(cfg.motion_file)

    def _spaces(self):
        self.obs_mask = conditioning_mask(self.cfg.conditioning)
        return sk.NUM_DOFS, {"policy": OBS_DIM, "critic": OBS_DIM}

    @property
    def step_dt(self) -> float:
        return 1.0 / CONTROL_HZ

    # ------------------------------------------------------------------------------------------------ building
    def _build(self) -> None:
        c, n, dev = self.cfg, self.num_envs, self.wp_device
        self.motion = motions.load_motions(c.motion_file, self.device)
        steps_per_clip = np.floor(self.motion.clip_duration / self.step_dt + 1e-6).astype(int)
        if c.eval_mode:
            # Episodes end only at a clip's end or on failure; the cap covers the longest clip.
            self.max_episode_length = int(steps_per_clip.max()) + 1
        options = SimOptions(
            substeps=c.substeps,
            control_dt=self.step_dt,
            nconmax=c.nconmax,
            njmax=c.njmax,
            iterations=c.solver_iterations,
            ls_iterations=c.solver_ls_iterations,
        )
        self.sim = HumanoidSim(n, dev, options)
        self.ref = self.motion.allocate_frames(n)

        frozen = np.zeros(sk.NUM_DOFS, dtype=bool)
        if c.freeze_hands_toes:
            for name in sk.FROZEN_HAND_TOE:
                body = sk.body_index(name)
                frozen[3 * (body - 1) : 3 * body] = True
        gains = np.repeat(sk.PD_GAINS[1:], 3, axis=0).astype(np.float32)
        eval_body = np.array([n_ in sk.EVAL_TERMINATION_BODIES for n_ in sk.BODY_NAMES], dtype=np.float32)
        self.action_scale: wp.array = wp.array(sk.ACTION_SCALE.astype(np.float32), dtype=float, device=dev)
        self.frozen_dof: wp.array = wp.array(frozen, dtype=wp.bool, device=dev)
        self.kp: wp.array = wp.array(gains[:, 0], dtype=float, device=dev)
        self.kd: wp.array = wp.array(gains[:, 1], dtype=float, device=dev)
        self.eval_body: wp.array = wp.array(eval_body, dtype=float, device=dev)
        self.mask: wp.array = wp.array(self.obs_mask, dtype=float, device=dev)

        self.clip_id = wp.zeros(n, dtype=int, device=dev)
        self.start_time = wp.zeros(n, dtype=float, device=dev)
        self.ref_time = wp.zeros(n, dtype=float, device=dev)
        self.obs_time = wp.zeros(n, dtype=float, device=dev)
        self.mpjpe_sum = wp.zeros(n, dtype=float, device=dev)
        self.reward_params = reward_params(c)

    # ------------------------------------------------------------------------------------------------ stepping
    def _step_impl(self) -> None:
        b, c, s, n = self.buffers, self.cfg, self.sim, self.num_envs
        # self.ref holds the reference of the observed frame (sampled at obs_time by the last step or reset).
        wp.launch(
            apply_actions_kernel,
            dim=(n, sk.NUM_DOFS),
            inputs=[b.actions, self.action_scale, self.frozen_dof, int(c.residual_actions), self.ref, s.joint_q],
            outputs=[s.joint_target],
        )
        s.simulate()
        wp.launch(
            advance_time_kernel,
            dim=n,
            inputs=[self.start_time, b.episode_length, self.step_dt],
            outputs=[self.ref_time],
        )
        self.motion.sample(self.clip_id, self.ref_time, self.ref)
        wp.launch(
            reward_and_termination_kernel,
            dim=n,
            inputs=[
                s.body_q,
                s.body_qd,
                s.body_com,
                s.joint_q,
                s.joint_qd,
                s.joint_target,
                self.kp,
                self.kd,
                EFFORT_LIMIT,
                self.ref,
                self.eval_body,
                self.clip_id,
                self.ref_time,
                self.motion.clip_duration_device,
                b.episode_length,
                int(c.eval_mode),
                c.termination_distance,
                c.eval_termination_distance,
                c.max_joint_speed,
                self.reward_params,
                self.mpjpe_sum,
            ],
            outputs=[
                b.rewards,
                b.terminated,
                b.truncated,
                b.metrics["success"],
                b.metrics["mpjpe_mm"],
                b.metrics["alive_steps"],
                b.reward_terms,
            ],
        )

    def _reset_impl(self, mask) -> None:
        """New episodes where ``mask`` is set (simulator set to the reference), then every env's observation."""
        b, s, n, r = self.buffers, self.sim, self.num_envs, self.ref
        wp.launch(
            start_episodes_kernel,
            dim=n,
            inputs=[
                mask,
                b.rng,
                self.motion.num_clips,
                self.motion.clip_duration_device,
                self.step_dt,
                int(self.cfg.eval_mode),
            ],
            outputs=[self.clip_id, self.start_time, self.ref_time, self.mpjpe_sum, s.reset_mask],
        )
        # Only the starting envs need the reference at their (new) start; every row is resampled below.
        self.motion.sample(self.clip_id, self.ref_time, r, mask=s.reset_mask)
        wp.launch(
            write_reference_state_kernel, dim=n, inputs=[s.reset_mask, r, s.root_com], outputs=[s.joint_q, s.joint_qd]
        )
        s.after_reset()
        wp.launch(_shift_time_kernel, dim=n, inputs=[self.ref_time, self.step_dt], outputs=[self.obs_time])
        self.motion.sample(self.clip_id, self.obs_time, r)
        wp.launch(
            observation_kernel,
            dim=(n, sk.NUM_BODIES),
            inputs=[s.body_q, s.body_qd, s.body_com, r, self.mask],
            outputs=[b.obs["critic"], b.obs["policy"]],
        )

    # ------------------------------------------------------------------------------------------------ inspection
    def reference_at(self, times: torch.Tensor | None = None):
        """Reference frames of every env at ``times`` (default: the current reference time); for tests and tools."""
        out = self.motion.allocate_frames(self.num_envs)
        t = self.ref_time if times is None else wp.from_torch(times.to(self.device, torch.float32).contiguous())
        assert isinstance(t, wp.array)  # from_torch returns a ctypes array_t only with return_ctype=True
        self.motion.sample(self.clip_id, t, out)
        return out


@wp.kernel
def _shift_time_kernel(ref_time: wp.array(dtype=float), dt: float, obs_time: wp.array(dtype=float)):
    i = wp.tid()
    obs_time[i] = ref_time[i] + dt
