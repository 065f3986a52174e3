"""The options of rsl_rl's classes, which cannot be edited here: one table (``RSL_RL_OPTIONS``) of option dataclasses,
each field made by ``option`` like every other option (``refpo_warp/utils/option_field.py``), read explicitly by
``option_fields`` (``refpo_warp/utils/options.py``) where a class's options are looked up.

rsl_rl's constructors accept anything and fail later (a zero ``num_mini_batches`` divides by zero in the middle of
training); these rules let the config resolver refuse such values up front. A field has no default of its own: the
constructor's is the default. Written against the parameters of rsl-rl-lib 5.0.1 to 5.5.1; a parameter one version
lacks is simply never checked there. Also here: the network rules every actor shares (hidden sizes, activations).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from enum import Enum
from typing import Any

import rsl_rl.modules as rsl_modules
from rsl_rl.algorithms import PPO as RslPPO
from rsl_rl.models import MLPModel

from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_field import choices, option
from refpo_warp.utils.option_rules import Check, Flag, Int, ListOf, OneOf, Real, check_options, mapping_or_none

OPTIMIZERS = ("adam", "adamw", "sgd", "rmsprop")  # rsl_rl.utils.resolve_optimizer


class Activation(str, Enum):
    """The activations of ``rsl_rl.utils.resolve_nn_activation``, by the names a config writes."""

    ELU = "elu"
    SELU = "selu"
    RELU = "relu"
    CRELU = "crelu"
    LRELU = "lrelu"
    TANH = "tanh"
    SIGMOID = "sigmoid"
    SOFTPLUS = "softplus"
    GELU = "gelu"
    SWISH = "swish"
    MISH = "mish"
    IDENTITY = "identity"


ACTIVATIONS = choices(Activation)
HIDDEN_DIMS = ListOf(Int(1, 65_536), min_len=1, max_len=64)


def check_distribution_cfg(key: str, value: Any) -> dict:
    """``distribution_cfg``: ``{class_name: <an rsl_rl Distribution>, <its options>}``, checked by its own rules."""
    from rsl_rl.utils import resolve_callable

    if not isinstance(value, dict) or "class_name" not in value:
        raise ConfigError(
            f"{key}={value!r} is invalid; expected a mapping with a class_name "
            f"(e.g. {{class_name: GaussianDistribution, init_std: 1.0}})"
        )
    try:
        cls = resolve_callable(value["class_name"])
    except (ImportError, AttributeError, ValueError, TypeError) as err:
        raise ConfigError(f"{key}.class_name={value['class_name']!r} cannot be resolved ({err})") from err
    if not (isinstance(cls, type) and issubclass(cls, rsl_modules.Distribution)):
        raise ConfigError(f"{key}.class_name={value['class_name']!r} is not an rsl_rl Distribution")
    rules = {
        f.name: f.metadata["rule"]
        for klass in cls.__mro__
        if klass in RSL_RL_OPTIONS
        for f in fields(RSL_RL_OPTIONS[klass])
    }
    options = {k: v for k, v in value.items() if k != "class_name"}
    for name in options:
        if name not in rules:
            raise unknown(f"option '{key}.{name}' for {cls.__name__}", f"{key}.{name}", [f"{key}.{k}" for k in rules])
    return {"class_name": value["class_name"], **check_options(rules, options, f"{key}.")}


@dataclass(frozen=True)
class RslPPOOptions:
    """rsl_rl's PPO arguments, which every algorithm here inherits (``OnPolicyAlgorithm`` subclasses rsl_rl's PPO)."""

    num_learning_epochs: int = option(rule=Int(1, 10_000))
    num_mini_batches: int = option(rule=Int(1, 1_000_000))
    clip_param: float = option(rule=Real(0, 10, lo_open=True))
    gamma: float = option(rule=Real(0, 1))
    lam: float = option(rule=Real(0, 1))
    value_loss_coef: float = option(rule=Real(0, 1e6))
    entropy_coef: float = option(rule=Real(0, 1e6))
    learning_rate: float = option(rule=Real(0, 1, lo_open=True))
    max_grad_norm: float = option(rule=Real(0, None, lo_open=True))
    # the saved optimizer state only loads into the same optimizer
    optimizer: str = option(rule=OneOf(OPTIMIZERS, fixed=True))
    use_clipped_value_loss: bool = option(rule=Flag())
    schedule: str = option(rule=OneOf("fixed", "adaptive"))
    desired_kl: float | None = option(rule=Real(0, None, lo_open=True, optional=True))
    normalize_advantage_per_mini_batch: bool = option(rule=Flag())
    use_mixed_precision: bool = option(rule=Flag())
    rnd_cfg: dict | None = option(rule=Check(mapping_or_none, "null or a mapping of RND options", optional=True))
    symmetry_cfg: dict | None = option(
        rule=Check(mapping_or_none, "null or a mapping of symmetry options", optional=True)
    )
    grad_reduce_bucket_mb: float = option(rule=Real(0, None, lo_open=True))
    share_cnn_encoders: bool | None = option(rule=Flag(optional=True))  # consumed by construct_algorithm


@dataclass(frozen=True)
class MLPModelOptions:
    """rsl_rl's ``MLPModel`` (the configs' critic, PPO's actor)."""

    hidden_dims: list[int] = option(rule=HIDDEN_DIMS)
    activation: str = option(rule=OneOf(Activation))
    obs_normalization: bool = option(rule=Flag())
    distribution_cfg: dict | None = option(
        rule=Check(check_distribution_cfg, "null or {class_name: <rsl_rl Distribution>, ...}", optional=True)
    )


@dataclass(frozen=True)
class GaussianDistributionOptions:
    init_std: float = option(rule=Real(0, 1e6, lo_open=True))
    std_range: list[float] = option(rule=ListOf(Real(0, None), min_len=2, max_len=2))
    std_type: str = option(rule=OneOf("scalar", "log"))
    learn_std: bool = option(rule=Flag())


@dataclass(frozen=True)
class BetaDistributionOptions:  # rsl-rl-lib >= 5.1
    action_range: list[float] = option(rule=ListOf(Real(), min_len=2, max_len=2))


RSL_RL_OPTIONS: dict[type, type] = {
    RslPPO: RslPPOOptions,
    MLPModel: MLPModelOptions,
    rsl_modules.GaussianDistribution: GaussianDistributionOptions,
}
if hasattr(rsl_modules, "BetaDistribution"):
    RSL_RL_OPTIONS[rsl_modules.BetaDistribution] = BetaDistributionOptions
