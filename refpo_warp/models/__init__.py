"""Policy models: the flow-matching actor (an rsl_rl model selected by class_name), its network and its export."""

from refpo_warp.models.flow_actor import CfmTerms, FlowActor, cfm_loss
from refpo_warp.models.flow_export import FlowSampler
from refpo_warp.models.phc_mlp_model import PhcMLPModel
from refpo_warp.models.velocity_field import SinusoidalEmbedding, TimestepEmbedding, VelocityField

__all__ = ["CfmTerms", "FlowActor", "FlowSampler", "PhcMLPModel", "SinusoidalEmbedding", "TimestepEmbedding", "VelocityField",
           "cfm_loss"]
