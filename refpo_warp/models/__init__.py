"""Policy models that rsl_rl selects by ``class_name`` (``refpo_warp.models:FlowActor``): the flow-matching actor,
ReinFlow's noisy-chain actor, the Puffer-PHC MLP and the empty critic of critic-free algorithms. Their networks, export
and diagnostics are the modules beside them."""

from refpo_warp.models.flow_actor import FlowActor
from refpo_warp.models.no_critic import NoCritic
from refpo_warp.models.phc_mlp_model import PhcMLPModel
from refpo_warp.models.reinflow_actor import ReinFlowActor

__all__ = ["FlowActor", "NoCritic", "PhcMLPModel", "ReinFlowActor"]
