"""On-policy algorithms selected by rsl_rl ``class_name``: ReFPO (FPO with reflow_coef=0), Gaussian PPO and
Flow-GRPO."""

from refpo_warp.algorithms.flow_grpo import FlowGRPO
from refpo_warp.algorithms.ppo import PPO
from refpo_warp.algorithms.refpo import ReFPO

__all__ = ["FlowGRPO", "PPO", "ReFPO"]
