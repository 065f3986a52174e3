"""mjlab config classes for the flow actor and ReFPO, and the ReFPO variant of a task's PPO runner config.

Each default has one home, the class (``FlowActor``'s constructor; ``ReFPO``'s and its shared update loop's
option fields): the two dataclasses are made from them, so every option is a flag of mjlab's ``train``
(``--agent.algorithm.reflow-coef 0.1``, ``--agent.actor.num-flow-steps 5``) with the class's default, and a new option
needs no edit here. A choice enum is a plain string flag (a config holds the string).
"""

from __future__ import annotations

import inspect
import sys
import typing
from dataclasses import field, fields, make_dataclass, replace
from enum import Enum

from mjlab.rl import RslRlModelCfg, RslRlOnPolicyRunnerCfg, RslRlPpoAlgorithmCfg

from refpo_warp.config.classes import POSITIONAL, class_defaults
from refpo_warp.utils.options import option_fields

ACTOR_CLASS = "refpo_warp.models:FlowActor"
ALGORITHM_CLASS = "refpo_warp.algorithms:ReFPO"
EXPERIMENT_SUFFIX = "_refpo"  # a variant's runs go to logs/rsl_rl/<task's experiment>_refpo/, beside the PPO runs


def _own_options(class_name: str, section: str, base: type) -> dict[str, tuple[object, typing.Any]]:
    """name -> (default, type) of the options that refpo_warp's classes in ``class_name``'s constructor chain declare
    (rsl_rl's own PPO keys keep mjlab's defaults unless ReFPO redeclares them); a key of ``base`` keeps its type."""
    base_types = {f.name: f.type for f in fields(base)}
    options = {}
    for name, (default, owner) in class_defaults(class_name).items():
        if name in POSITIONAL[section] or not owner.__module__.startswith("refpo_warp."):
            continue
        options[name] = (default, base_types.get(name) or _hint(owner, name))
    return options


def _hint(owner: type, name: str) -> typing.Any:
    """The declared type of an option: its field's (``refpo_warp/utils/options.py``) or its constructor parameter's; a
    choice enum's is ``str``."""
    if name in option_fields(owner):
        declared = owner.__dict__.get("Options", owner)  # a model's Options dataclass, or the class body
        namespace = vars(sys.modules[owner.__module__])
        hint = eval(declared.__annotations__[name], namespace) if name in declared.__annotations__ else None
        if hint is None:  # a field inherited by a model's Options
            hint = typing.get_type_hints(declared)[name]
    else:
        hint = typing.get_type_hints(inspect.getattr_static(owner, "__init__"))[name]  # owner.__init__, unbound
    args = typing.get_args(hint)
    if isinstance(hint, type) and issubclass(hint, Enum):
        return str
    if any(isinstance(a, type) and issubclass(a, Enum) for a in args):
        return str | None
    return hint


def _config_class(name: str, base: type, class_name: str, options: dict, doc: str) -> type:
    specs = [("class_name", str, field(default=class_name))]
    specs += [(key, hint, field(default=default)) for key, (default, hint) in options.items()]
    cls = make_dataclass(name, specs, bases=(base,))
    cls.__module__, cls.__doc__ = __name__, doc  # importable by name (pickled configs), and --help's text
    return cls


_ACTOR_OPTIONS = _own_options(ACTOR_CLASS, "actor", RslRlModelCfg)
_ALGORITHM_OPTIONS = _own_options(ALGORITHM_CLASS, "algorithm", RslRlPpoAlgorithmCfg)

FlowActorCfg = _config_class(
    "FlowActorCfg",
    RslRlModelCfg,
    ACTOR_CLASS,
    _ACTOR_OPTIONS,
    "mjlab's model config for refpo_warp.models:FlowActor: its constructor's options and defaults.",
)
ReFPOAlgorithmCfg = _config_class(
    "ReFPOAlgorithmCfg",
    RslRlPpoAlgorithmCfg,
    ALGORITHM_CLASS,
    _ALGORITHM_OPTIONS,
    "mjlab's algorithm config for refpo_warp.algorithms:ReFPO: its constructor's options and defaults (a fixed "
    "learning rate, no entropy term, ReFPO's clip); rsl_rl's other PPO keys as mjlab's.",
)

# The PPO keys whose values ReFPO declares itself (clip_param, learning_rate, schedule, entropy_coef,
# use_clipped_value_loss): a variant takes ReFPO's. Why: they are tuned to the CFM proxy ratio, and PPO's adaptive
# schedule, driven by that ratio's KL estimate, moves the learning rate to its bounds (docs/rsl_rl_users.md).
# Every other PPO key (gamma, lam, epochs, minibatches, value and gradient settings) is the task's.
REFPO_PPO_KEYS = tuple(f.name for f in fields(RslRlPpoAlgorithmCfg) if f.name in _ALGORITHM_OPTIONS)


def algo_deltas(algo: str) -> dict:
    """The algorithm options ``configs/algo/<algo>.yaml`` sets beyond ReFPO's own file (its ``base`` chain after
    ``refpo``), e.g. ``refpo_onestep``'s one-step term: the one home of a named ReFPO configuration."""
    from refpo_warp.config.config_set import config_set

    chain = config_set().algo_chain(algo)
    if chain[0].name != "refpo":
        raise ValueError(
            f"algo '{algo}' does not derive from refpo: an mjlab ReFPO variant takes a configuration of ReFPO's"
        )
    deltas: dict = {}
    for file in chain[1:]:
        deltas.update({k: v for k, v in (file.data.get("algorithm") or {}).items() if k != "class_name"})
    return deltas


def refpo_runner_cfg(ppo_cfg: RslRlOnPolicyRunnerCfg, algo: str = "refpo") -> RslRlOnPolicyRunnerCfg:
    """The ReFPO variant of a task's PPO runner config: the actor becomes a FlowActor of the task's sizes
    (hidden_dims, activation, obs_normalization), the algorithm ReFPO with the task's PPO keys except
    ``REFPO_PPO_KEYS`` (and the options of ``algo``'s file, a configuration of ReFPO's: ``algo_deltas``); the
    critic, the rollout and everything else of the runner config stay the task's."""
    if not isinstance(ppo_cfg, RslRlOnPolicyRunnerCfg):
        raise TypeError(f"refpo_runner_cfg needs an RslRlOnPolicyRunnerCfg (an on-policy task), got {type(ppo_cfg)}")
    actor = ppo_cfg.actor
    if actor.cnn_cfg is not None or actor.rnn_type is not None:
        raise ValueError(
            "FlowActor is an MLP over flat observations; the task's actor sets "
            f"cnn_cfg={actor.cnn_cfg!r}, rnn_type={actor.rnn_type!r} (valid for a ReFPO variant: both None)"
        )
    flow_actor = FlowActorCfg(
        hidden_dims=tuple(actor.hidden_dims), activation=actor.activation, obs_normalization=actor.obs_normalization
    )
    task_keys = {
        f.name: getattr(ppo_cfg.algorithm, f.name)
        for f in fields(RslRlPpoAlgorithmCfg)
        if f.name != "class_name" and f.name not in REFPO_PPO_KEYS
    }
    suffix = EXPERIMENT_SUFFIX + ("" if algo == "refpo" else algo.removeprefix("refpo"))
    return replace(
        ppo_cfg,
        actor=flow_actor,
        algorithm=ReFPOAlgorithmCfg(**task_keys, **algo_deltas(algo)),
        experiment_name=ppo_cfg.experiment_name + suffix,
    )
