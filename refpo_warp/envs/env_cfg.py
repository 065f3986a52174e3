"""``EnvCfg``: the options every environment shares. Warp-free, so a config resolves without loading a simulator."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import MISSING, dataclass, fields
from typing import Any

from refpo_warp.utils.errors import unknown
from refpo_warp.utils.option_rules import Flag, Int, OneOf, check_options, rules_for

ACTION_TRANSFORMS = ("clip", "tanh")


@dataclass
class EnvCfg:
    """Options shared by every environment; task cfgs subclass this."""

    max_episode_length: int = 1000
    graph_capture: bool = True
    """Replay the step as a captured graph after one eager warm-up step (CUDA graph or Warp CPU graph)."""
    action_transform: str = "clip"
    """What the env does with the policy's actions before its dynamics: ``clip`` to [-1, 1] (the task kernels
    clip), or ``tanh`` first (MuJoCo Playground sends tanh(action) to the env; the learner keeps the pre-tanh
    action, so every algorithm trains on what it sampled)."""
    reset_group_size: int = 1
    """Envs [g G, (g + 1) G) form group g: the k-th episode of every member starts from the same initial state (one
    random stream per group and episode index; Flow-GRPO's groups). 1: an independent stream per env."""
    action_chunk: int = 1
    """Env steps per policy action: above 1, ``refpo_warp.envs.registry.make_env`` wraps the env in an
    ``ActionChunkWrapper`` whose actions are ``action_chunk`` env actions run open-loop (ReinFlow's horizon)."""

    # Valid values of the fields (refpo_warp.utils.option_rules); a subclass adds the rules of its own fields likewise.
    option_rules = {
        "max_episode_length": Int(1, 10_000_000),
        "graph_capture": Flag(),
        "action_transform": OneOf(ACTION_TRANSFORMS),
        "reset_group_size": Int(1, 1_000_000),
        "action_chunk": Int(1, 1000, fixed=True),
    }  # the chunk sets the policy's action size

    def __post_init__(self) -> None:
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        for name, value in check_options(rules_for(type(self)), values, "env.").items():
            object.__setattr__(self, name, value)

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        """Every option and its default value."""
        return {f.name: f.default for f in fields(cls) if f.default is not MISSING}

    @classmethod
    def check_keys(cls, keys: Iterable[str], what: str, prefix: str = "") -> None:
        """Refuse a key that is not an option of this cfg, naming the closest one (``what`` says whose option)."""
        valid = [f.name for f in fields(cls)]
        for key in keys:
            if key not in valid:
                raise unknown(what, f"{prefix}{key}", [f"{prefix}{k}" for k in valid])
