"""Policy models (rsl_rl models selected by class_name): the flow-matching actor, its network and its export, ReinFlow's
noisy-chain actor, and the empty critic of critic-free algorithms."""

from refpo_warp.models.flow_actor import CfmTerms, FlowActor, cfm_loss
from refpo_warp.models.flow_export import FlowSampler
from refpo_warp.models.no_critic import NoCritic
from refpo_warp.models.phc_mlp_model import PhcMLPModel
from refpo_warp.models.reinflow_actor import ReinFlowActor
from refpo_warp.models.velocity_field import SinusoidalEmbedding, TimestepEmbedding, VelocityField

__all__ = ["CfmTerms", "FlowActor", "FlowSampler", "NoCritic", "PhcMLPModel", "ReinFlowActor", "SinusoidalEmbedding",
           "TimestepEmbedding", "VelocityField", "cfm_loss"]
