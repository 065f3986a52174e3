"""Option rules of the run options in ``configs/default.yaml`` (everything outside the class and env sections),
and the checks that involve several options. See ``refpo_warp.utils.option_rules`` for the rule types.

A new key in ``default.yaml`` gets its rule here (``tests/utils/test_option_rules.py`` fails for a key without one).
"""

from __future__ import annotations

import importlib.util
from typing import Any

from refpo_warp.models.sampled_policy import NOISE_PROTOCOLS_RULE, NUM_FLOW_STEPS
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Check, Flag, Int, ListOf, OneOf, Real, Text

MAX_ENVS = 1 << 22  # 4M envs: far above what one GPU holds, low enough to catch a typo before allocating
MAX_TRANSITIONS = 1 << 28  # num_envs x num_steps_per_env held in the rollout storage
FLOW_STEPS = ListOf(NUM_FLOW_STEPS, min_len=1, max_len=32)


def _check_device(key: str, value: Any) -> str:
    # The name only: resolve_config checks that the device exists on this machine when it resolves for this
    # machine (device_type not given); a config resolved for another machine's device type (sweeps) is not.
    from refpo_warp.utils.device import check_device_name

    return check_device_name(value)


def _check_logger(key: str, value: Any) -> str:
    if value not in ("tensorboard", "wandb", "neptune"):
        raise ConfigError(f"{key}={value!r} is invalid; expected one of 'tensorboard', 'wandb', 'neptune'")
    package = {"wandb": "wandb", "neptune": "neptune"}.get(value)
    if package and importlib.util.find_spec(package) is None:
        raise ConfigError(
            f"{key}={value} needs the '{package}' package, which is not installed; use tensorboard "
            f"or pip install {package}"
        )
    return value


def _check_notice(key: str, value: Any) -> str:
    if not isinstance(value, str):
        raise ConfigError(f"{key}={value!r} is invalid; expected a text")
    try:
        value.format(task="task", algo="algo")
    except (KeyError, IndexError, ValueError) as err:
        raise ConfigError(
            f"{key}={value!r} is invalid ({type(err).__name__}: {err}); only {{task}} and {{algo}} are "
            f"filled in (write {{{{ and }}}} for literal braces)"
        ) from None
    return value


def _check_obs_groups(key: str, value: Any) -> dict:
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise ConfigError(f"{key}={value!r} is invalid; expected a mapping like {{actor: [policy], critic: [policy]}}")
    for name, groups in value.items():
        if not isinstance(groups, list) or not groups or not all(isinstance(g, str) for g in groups):
            raise ConfigError(
                f"{key}.{name}={groups!r} is invalid; expected a non-empty list of observation group names"
            )
    return value


RUN_RULES = {
    "seed": Int(0, 2**32 - 1),  # numpy's seed range
    "device": Check(_check_device, "auto, cpu, cuda or cuda:N"),
    "num_envs": Int(1, MAX_ENVS),
    "total_env_steps": Int(1, 10**13),
    "max_iterations": Int(1, 10**8, optional=True),
    "run_dir": Text(optional=True),
    "resume": Flag(),
    "verbose": Flag(),
    "init_from": Text(optional=True),  # the run dir itself is checked when training starts (training/init_from.py)
    "critic_warmup_iterations": Int(0, 10**8),
    "config_dir": Text(optional=True),  # the folder itself is checked when the config path is built
    "notice": Check(_check_notice, "null or a text ({task} and {algo} are filled in)", optional=True),
    "runner.num_steps_per_env": Int(1, 1_000_000),
    "runner.save_interval": Int(1, 10**8),
    "runner.logger": Check(_check_logger, "tensorboard, wandb or neptune"),
    "runner.check_for_nan": Flag(),
    # rsl_rl refuses the CUDA-graph modes "reduce-overhead" and "max-autotune"
    "runner.torch_compile_mode": OneOf(None, "default", "max-autotune-no-cudagraphs"),
    "runner.obs_groups": Check(_check_obs_groups, "a mapping {set: [observation groups]}", fixed=True),
    "runner.init_at_random_ep_len": Flag(),
    "runner.log_full": Flag(),
    "pretrain.dataset": Text(optional=True),  # read and checked by refpo pretrain (demonstrations/dataset_file.py)
    "pretrain.epochs": Int(1, 10**6),
    "pretrain.batch_size": Int(1, 1 << 24),
    "pretrain.learning_rate": Real(0, 10, lo_open=True),
    "pretrain.validation_fraction": Real(0, 1, lo_open=True, hi_open=True),
    "pretrain.patience": Int(1, 10**6),
    "pretrain.num_pairs": Int(1, 4096, optional=True),
    "eval.at_end": Flag(),
    "eval.flow_steps": FLOW_STEPS,
    "eval.num_envs": Int(1, MAX_ENVS, optional=True),
    "eval.max_steps": Int(1, 10**8, optional=True),
    "eval.initial_noise": NOISE_PROTOCOLS_RULE,
    "eval.perturbation": Flag(),
    "eval.interval": Int(0, 10**8, optional=True),
    "eval.interval_flow_steps": FLOW_STEPS,
    "eval.interval_num_envs": Int(1, MAX_ENVS),
}
# Keys checked elsewhere: task and algo (by name, against the registry and configs/algo), the sections env, actor,
# critic, algorithm (against their classes' rules), eval.env (against the task's env cfg) and video (VideoOptions).
NOT_RULED = ("task", "algo", "env", "actor", "critic", "algorithm", "eval.env", "video")


def check_combinations(cfg: dict) -> None:
    """Checks that involve several options of a resolved config; each error names all the keys involved."""
    envs, steps = cfg["num_envs"], cfg["runner"]["num_steps_per_env"]
    if envs * steps > MAX_TRANSITIONS:
        raise ConfigError(
            f"num_envs x runner.num_steps_per_env = {envs} x {steps} = {envs * steps:,} transitions per "
            f"iteration is more than {MAX_TRANSITIONS:,}; lower one of them"
        )
    mini = cfg["algorithm"].get("num_mini_batches")
    if mini is not None and mini > envs * steps:
        raise ConfigError(
            f"algorithm.num_mini_batches={mini} is more than the {envs * steps} transitions per "
            f"iteration (num_envs={envs} x runner.num_steps_per_env={steps}): a minibatch would be "
            f"empty"
        )
