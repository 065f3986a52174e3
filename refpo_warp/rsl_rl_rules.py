"""Option rules for the rsl_rl classes the configs select (PPO, MLPModel, output distributions).

rsl_rl's constructors accept anything and fail later (a zero ``num_mini_batches`` divides by zero in the middle
of training); these rules let the config resolver refuse such values up front. Our subclasses
(``refpo_warp.algorithms:PPO`` and ``ReFPO``) inherit them. Written against the parameters of rsl-rl-lib 5.0.1
to 5.5.1; a parameter one version lacks is simply never checked there.
"""

from __future__ import annotations

from typing import Any

import rsl_rl.modules as rsl_modules
from rsl_rl.algorithms import PPO as RslPPO
from rsl_rl.models import MLPModel

from refpo_warp.errors import ConfigError, unknown
from refpo_warp.options import Check, Flag, Int, ListOf, OneOf, Real, check_options, register_rules, rules_for

ACTIVATIONS = ("elu", "selu", "relu", "crelu", "lrelu", "tanh", "sigmoid", "softplus", "gelu", "swish", "mish",
               "identity")  # fmt: skip  (rsl_rl.utils.resolve_nn_activation)
OPTIMIZERS = ("adam", "adamw", "sgd", "rmsprop")  # rsl_rl.utils.resolve_optimizer
HIDDEN_DIMS = ListOf(Int(1, 65_536), min_len=1, max_len=64)


def mapping_or_none(key: str, value: Any) -> Any:
    if value is not None and not isinstance(value, dict):
        raise ConfigError(f"{key}={value!r} is invalid; expected null or a mapping of options")
    return value


def check_distribution_cfg(key: str, value: Any) -> dict:
    """``distribution_cfg``: ``{class_name: <an rsl_rl Distribution>, <its options>}``, checked by its own rules."""
    from rsl_rl.utils import resolve_callable

    if not isinstance(value, dict) or "class_name" not in value:
        raise ConfigError(f"{key}={value!r} is invalid; expected a mapping with a class_name "
                          f"(e.g. {{class_name: GaussianDistribution, init_std: 1.0}})")  # fmt: skip
    try:
        cls = resolve_callable(value["class_name"])
    except (ImportError, AttributeError, ValueError, TypeError) as err:
        raise ConfigError(f"{key}.class_name={value['class_name']!r} cannot be resolved ({err})") from err
    if not (isinstance(cls, type) and issubclass(cls, rsl_modules.Distribution)):
        raise ConfigError(f"{key}.class_name={value['class_name']!r} is not an rsl_rl Distribution")
    rules = rules_for(cls)
    options = {k: v for k, v in value.items() if k != "class_name"}
    for name in options:
        if name not in rules:
            raise unknown(f"option '{key}.{name}' for {cls.__name__}", f"{key}.{name}", [f"{key}.{k}" for k in rules])
    return {"class_name": value["class_name"], **check_options(rules, options, f"{key}.")}


register_rules(RslPPO, {
    "num_learning_epochs": Int(1, 10_000),
    "num_mini_batches": Int(1, 1_000_000),
    "clip_param": Real(0, 10, lo_open=True),
    "gamma": Real(0, 1),
    "lam": Real(0, 1),
    "value_loss_coef": Real(0, 1e6),
    "entropy_coef": Real(0, 1e6),
    "learning_rate": Real(0, 1, lo_open=True),
    "max_grad_norm": Real(0, None, lo_open=True),
    "optimizer": OneOf(OPTIMIZERS, fixed=True),  # the saved optimizer state only loads into the same optimizer
    "use_clipped_value_loss": Flag(),
    "schedule": OneOf("fixed", "adaptive"),
    "desired_kl": Real(0, None, lo_open=True, optional=True),
    "normalize_advantage_per_mini_batch": Flag(),
    "use_mixed_precision": Flag(),
    "rnd_cfg": Check(mapping_or_none, "null or a mapping of RND options", optional=True),
    "symmetry_cfg": Check(mapping_or_none, "null or a mapping of symmetry options", optional=True),
    "grad_reduce_bucket_mb": Real(0, None, lo_open=True),
    "share_cnn_encoders": Flag(optional=True),  # consumed by construct_algorithm
})  # fmt: skip

register_rules(MLPModel, {
    "hidden_dims": HIDDEN_DIMS,
    "activation": OneOf(ACTIVATIONS),
    "obs_normalization": Flag(),
    "distribution_cfg": Check(check_distribution_cfg, "null or {class_name: <rsl_rl Distribution>, ...}",
                              optional=True),
})  # fmt: skip

_STD_RANGE = ListOf(Real(0, None), min_len=2, max_len=2)
register_rules(rsl_modules.GaussianDistribution, {
    "init_std": Real(0, 1e6, lo_open=True),
    "std_range": _STD_RANGE,
    "std_type": OneOf("scalar", "log"),
    "learn_std": Flag(),
})  # fmt: skip
if hasattr(rsl_modules, "BetaDistribution"):  # rsl-rl-lib >= 5.1
    register_rules(rsl_modules.BetaDistribution, {"action_range": ListOf(Real(), min_len=2, max_len=2)})
