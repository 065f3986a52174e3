"""On-policy algorithms selected by rsl_rl ``class_name``: ReFPO (FPO with reflow_coef=0), its advantage-weighted
variant, FPO++ (ReFPO on FPO++ with reflow_coef > 0), Gaussian PPO, and the flow baselines Flow-GRPO and ReinFlow."""

from refpo_warp.algorithms.flow_grpo import FlowGRPO
from refpo_warp.algorithms.fpo_pp import FPOPlusPlus
from refpo_warp.algorithms.ppo import PPO
from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.algorithms.refpo_aw import AdvantageWeightedReFPO
from refpo_warp.algorithms.reinflow import ReinFlow

__all__ = ["PPO", "AdvantageWeightedReFPO", "FPOPlusPlus", "FlowGRPO", "ReFPO", "ReinFlow"]
