"""Options of the humanoid tracking env (Warp-free): conditioning, motion source, episode ends, reward terms, solver.

The reward is a sum of named terms (``REWARD_TERMS``; kernels in ``reward_terms.py``) whose weights and scales are
options here; their sums over each episode are logged as ``Episode_Reward/<term>``.
"""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.tasks.humanoid.obs_layout import CONDITIONING_REGIMES
from refpo_warp.utils.option_rules import Flag, Int, OneOf, Real, Text

REWARD_TERMS = ("pos", "rot", "vel", "angvel", "power")


@dataclass
class HumanoidTrackingCfg(EnvCfg):
    conditioning: str = "all"
    """Goal conditioning of the policy observation: all | root_hands | root (set by the task id)."""
    motion_file: str = ""
    """AMASS npz file, folder of them, or *.motionlib.npz; "" = the shipped synthetic clips, shipped:<file> = one."""
    eval_mode: bool = False
    """Env i plays clip i from its start (no random init); termination on the mean body distance."""
    max_episode_length: int = 300
    """Training episode cap in control steps (the reference crops clips to 300 frames); unused in eval mode."""
    termination_distance: float = 0.25
    """Training: the episode ends when any body is farther than this (m) from the reference."""
    eval_termination_distance: float = 0.5
    """Eval mode: the episode ends when the mean distance of the 20 non-hand/toe bodies exceeds this (m)."""
    reward_pos_weight: float = 0.5
    reward_pos_scale: float = 100.0
    """Term ``pos``: weight * exp(-scale * mean squared body-position error, m^2)."""
    reward_rot_weight: float = 0.3
    reward_rot_scale: float = 10.0
    """Term ``rot``: weight * exp(-scale * mean squared body-rotation angle, rad^2)."""
    reward_vel_weight: float = 0.1
    reward_vel_scale: float = 0.1
    """Term ``vel``: weight * exp(-scale * mean squared body linear-velocity error, (m/s)^2)."""
    reward_angvel_weight: float = 0.1
    reward_angvel_scale: float = 0.1
    """Term ``angvel``: weight * exp(-scale * mean squared body angular-velocity error, (rad/s)^2)."""
    power_coef: float = 0.0005
    """Term ``power``: -power_coef * sum over hinges of |PD torque * joint rate| (off for the first 3 steps)."""
    freeze_hands_toes: bool = True
    """L/R_Hand and L/R_Toe PD targets stay 0 (the reference's freeze_hand / freeze_toe)."""
    residual_actions: bool = False
    """PD target = the reference joint angles of the observed frame (one control step ahead) + scale * clip(a, -1, 1),
    kept within pi/2 of the current joint angles: Puffer-PHC's ``res_action`` (off in the paper's runs, as here by
    default). Off: PD target = scale * clip(a, -1, 1)."""
    max_joint_speed: float = 100.0
    """A hinge rate above this (rad/s) is a numerical blow-up: the episode ends as a failure."""
    substeps: int = 4
    """Physics steps per 30 Hz control step (120 Hz; 3 substeps fail the 3 s PD hold, see docs/humanoid.md)."""
    nconmax: int = 32
    """Contact points per world; MuJoCo Warp pools nconmax x num_envs for all worlds (measured: at most 14 per world
    on average over 32 tracking worlds). Kernels sized by the pool run over every slot, used or not."""
    njmax: int = 160
    """Constraint rows per world (4 per pyramidal contact + joint limits); measured peaks 72 (training) and 108 (eval
    mode) under N(0, 1) actions. Kernels sized by njmax run over every row, used or not (320 -> 160: +5% steps/s,
    identical results)."""
    solver_iterations: int = 100
    """Newton solver iteration cap (MuJoCo's default); worlds stop at convergence (1.8 iterations on average).
    Capping at 3 moves bodies by up to 0.15 m in one control step from a cold start: not a safe speed-up."""
    solver_ls_iterations: int = 50

    option_rules = {  # valid values (refpo_warp.utils.option_rules)
        "conditioning": OneOf(CONDITIONING_REGIMES, fixed=True),
        "motion_file": Text(),
        "eval_mode": Flag(),
        "termination_distance": Real(0, 100, lo_open=True),
        "eval_termination_distance": Real(0, 100, lo_open=True),
        **{f"reward_{t}_weight": Real(-1e6, 1e6) for t in REWARD_TERMS[:4]},
        **{f"reward_{t}_scale": Real(0, 1e6) for t in REWARD_TERMS[:4]},
        "power_coef": Real(0, 1e3),
        "freeze_hands_toes": Flag(),
        "residual_actions": Flag(),
        "max_joint_speed": Real(0, 1e6, lo_open=True),
        "substeps": Int(1, 100),
        "nconmax": Int(1, 100_000),
        "njmax": Int(1, 1_000_000),
        "solver_iterations": Int(1, 10_000),
        "solver_ls_iterations": Int(0, 10_000),
    }
