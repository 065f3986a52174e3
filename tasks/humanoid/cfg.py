"""Options of the humanoid tracking env (Warp-free): conditioning, motion source, episode ends, reward terms, solver.

The reward is a sum of named terms (``REWARD_TERMS``; kernels in ``reward_terms.py``) whose weights and scales are
options here; their sums over each episode are logged as ``Episode_Reward/<term>``.
"""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.tasks.humanoid.obs_layout import CONDITIONING_REGIMES
from refpo_warp.utils.option_rules import Flag, Int, OneOf, Real, Text
from refpo_warp.utils.options import option

REWARD_TERMS = ("pos", "rot", "vel", "angvel", "power")
_WEIGHT, _SCALE = Real(-1e6, 1e6), Real(0, 1e6)


@dataclass
class HumanoidTrackingCfg(EnvCfg):
    conditioning: str = option(
        "all",
        OneOf(CONDITIONING_REGIMES, fixed=True),
        "goal conditioning of the policy observation: all | root_hands | root (set by the task id)",
    )
    motion_file: str = option(
        "",
        Text(),
        'AMASS npz file, folder of them, or *.motionlib.npz; "" = the shipped synthetic clips, shipped:<file> = one',
    )
    eval_mode: bool = option(
        False, Flag(), "env i plays clip i from its start (no random init); termination on the mean body distance"
    )
    max_episode_length: int = option(
        300, doc="training episode cap in control steps (the reference crops clips to 300 frames); unused in eval mode"
    )
    termination_distance: float = option(
        0.25,
        Real(0, 100, lo_open=True),
        "training: the episode ends when any body is farther than this (m) from the reference",
    )
    eval_termination_distance: float = option(
        0.5,
        Real(0, 100, lo_open=True),
        "eval mode: the episode ends when the mean distance of the 20 non-hand/toe bodies exceeds this (m)",
    )
    reward_pos_weight: float = option(0.5, _WEIGHT, "weight of term pos")
    reward_pos_scale: float = option(
        100.0, _SCALE, "term pos: weight * exp(-scale * mean squared body-position error, m^2)"
    )
    reward_rot_weight: float = option(0.3, _WEIGHT, "weight of term rot")
    reward_rot_scale: float = option(
        10.0, _SCALE, "term rot: weight * exp(-scale * mean squared body-rotation angle, rad^2)"
    )
    reward_vel_weight: float = option(0.1, _WEIGHT, "weight of term vel")
    reward_vel_scale: float = option(
        0.1, _SCALE, "term vel: weight * exp(-scale * mean squared body linear-velocity error, (m/s)^2)"
    )
    reward_angvel_weight: float = option(0.1, _WEIGHT, "weight of term angvel")
    reward_angvel_scale: float = option(
        0.1, _SCALE, "term angvel: weight * exp(-scale * mean squared body angular-velocity error, (rad/s)^2)"
    )
    power_coef: float = option(
        0.0005,
        Real(0, 1e3),
        "term power: -power_coef * sum over hinges of |PD torque * joint rate| (off for the first 3 steps)",
    )
    freeze_hands_toes: bool = option(
        True, Flag(), "L/R_Hand and L/R_Toe PD targets stay 0 (the reference's freeze_hand / freeze_toe)"
    )
    residual_actions: bool = option(
        False,
        Flag(),
        "PD target = the reference joint angles of the observed frame (one control step ahead) + scale * clip(a, -1, "
        "1), kept within pi/2 of the current joint angles: Puffer-PHC's res_action (off in the paper's runs, as here "
        "by default). Off: PD target = scale * clip(a, -1, 1)",
    )
    max_joint_speed: float = option(
        100.0,
        Real(0, 1e6, lo_open=True),
        "a hinge rate above this (rad/s) is a numerical blow-up: the episode ends as a failure",
    )
    substeps: int = option(
        4,
        Int(1, 100),
        "physics steps per 30 Hz control step (120 Hz; 3 substeps fail the 3 s PD hold, see docs/humanoid.md)",
    )
    nconmax: int = option(
        32,
        Int(1, 100_000),
        "contact points per world; MuJoCo Warp pools nconmax x num_envs for all worlds (measured: at most 14 per "
        "world on average over 32 tracking worlds). Kernels sized by the pool run over every slot, used or not",
    )
    njmax: int = option(
        160,
        Int(1, 1_000_000),
        "constraint rows per world (4 per pyramidal contact + joint limits); measured peaks 72 (training) and 108 "
        "(eval mode) under N(0, 1) actions. Kernels sized by njmax run over every row, used or not (320 -> 160: +5% "
        "steps/s, identical results)",
    )
    solver_iterations: int = option(
        100,
        Int(1, 10_000),
        "Newton solver iteration cap (MuJoCo's default); worlds stop at convergence (1.8 iterations on average). "
        "Capping at 3 moves bodies by up to 0.15 m in one control step from a cold start: not a safe speed-up",
    )
    solver_ls_iterations: int = option(50, Int(0, 10_000), "Newton line-search iteration cap")
