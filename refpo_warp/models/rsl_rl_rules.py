"""Option rules for the rsl_rl models the configs select (``MLPModel`` and its output distributions), and the rules of
the network options every actor here shares (hidden sizes, activations).

rsl_rl's constructors accept anything and fail later; these rules let the config resolver refuse such values up
front. Written against the parameters of rsl-rl-lib 5.0.1 to 5.5.1; a parameter one version lacks is simply never
checked there. The rules of rsl_rl's PPO are in ``refpo_warp/algorithms/rsl_rl_rules.py``.
"""

from __future__ import annotations

from enum import Enum
from typing import Any

import rsl_rl.modules as rsl_modules
from rsl_rl.models import MLPModel

from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import (
    Check,
    Flag,
    Int,
    ListOf,
    OneOf,
    Real,
    check_options,
    register_rules,
    rules_for,
)
from refpo_warp.utils.options import choices


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
    rules = rules_for(cls)
    options = {k: v for k, v in value.items() if k != "class_name"}
    for name in options:
        if name not in rules:
            raise unknown(f"option '{key}.{name}' for {cls.__name__}", f"{key}.{name}", [f"{key}.{k}" for k in rules])
    return {"class_name": value["class_name"], **check_options(rules, options, f"{key}.")}


register_rules(
    MLPModel,
    {
        "hidden_dims": HIDDEN_DIMS,
        "activation": OneOf(Activation),
        "obs_normalization": Flag(),
        "distribution_cfg": Check(
            check_distribution_cfg, "null or {class_name: <rsl_rl Distribution>, ...}", optional=True
        ),
    },
)

_STD_RANGE = ListOf(Real(0, None), min_len=2, max_len=2)
register_rules(
    rsl_modules.GaussianDistribution,
    {
        "init_std": Real(0, 1e6, lo_open=True),
        "std_range": _STD_RANGE,
        "std_type": OneOf("scalar", "log"),
        "learn_std": Flag(),
    },
)
if hasattr(rsl_modules, "BetaDistribution"):  # rsl-rl-lib >= 5.1
    register_rules(rsl_modules.BetaDistribution, {"action_range": ListOf(Real(), min_len=2, max_len=2)})
