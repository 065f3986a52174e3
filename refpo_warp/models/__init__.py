"""Policy models: the flow-matching actor (an rsl_rl model selected by class_name) and its velocity network."""

from refpo_warp.models.flow_actor import FlowActor, FlowSampler
from refpo_warp.models.velocity_field import SinusoidalEmbedding, VelocityField

__all__ = ["FlowActor", "FlowSampler", "SinusoidalEmbedding", "VelocityField"]
