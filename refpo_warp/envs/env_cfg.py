"""``EnvCfg``: the options every environment shares. Warp-free, so a config resolves without loading a simulator.

Each option is a field made by ``option(default, rule, doc)`` (``refpo_warp/utils/options.py``); a task's cfg subclasses
``EnvCfg`` and declares its own the same way. A value that differs per task is set in ``configs/task/*.yaml``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import MISSING, dataclass, fields
from typing import Any

from refpo_warp.utils.errors import unknown
from refpo_warp.utils.option_rules import Flag, Int, OneOf
from refpo_warp.utils.options import check_fields, option

ACTION_TRANSFORMS = ("clip", "tanh")


@dataclass
class EnvCfg:
    """Options shared by every environment; task cfgs subclass this."""

    max_episode_length: int = option(1000, Int(1, 10_000_000), "episode time-out in env steps")
    graph_capture: bool = option(
        True, Flag(), "replay the step as a captured graph after one eager warm-up step (CUDA graph or Warp CPU graph)"
    )
    action_transform: str = option(
        "clip",
        OneOf(ACTION_TRANSFORMS),
        "what the env does with the policy's actions before its dynamics: clip to [-1, 1] (the task kernels clip), or "
        "tanh first (MuJoCo Playground sends tanh(action) to the env; the learner keeps the pre-tanh action, so every "
        "algorithm trains on what it sampled)",
    )
    reset_group_size: int = option(
        1,
        Int(1, 1_000_000),
        "envs [g G, (g + 1) G) form group g: the k-th episode of every member starts from the same initial state (one "
        "random stream per group and episode index; Flow-GRPO's groups); 1: an independent stream per env",
    )
    action_chunk: int = option(
        1,
        Int(1, 1000, fixed=True),  # the chunk sets the policy's action size
        "env steps per policy action: above 1, refpo_warp.envs.registry.make_env wraps the env in an "
        "ActionChunkWrapper whose actions are action_chunk env actions run open-loop (ReinFlow's horizon)",
    )

    def __post_init__(self) -> None:
        check_fields(self, "env.")

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
