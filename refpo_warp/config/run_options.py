"""The run options of ``configs/default.yaml`` (everything outside the class, env and video sections), declared like
every other option: a field with its rule and doc (``refpo_warp/utils/options.py``), its default being
``default.yaml``'s; a section of keys (``runner.*``) is a dataclass of its own. Also the checks that involve several
options.

A new key in ``default.yaml`` gets its field here (``tests/utils/test_option_rules.py`` fails for a key without one).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from enum import Enum
from typing import Any

from refpo_warp.models.sampled_policy import NOISE_PROTOCOLS_RULE, NUM_FLOW_STEPS
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Check, Flag, Int, ListOf, OneOf, Real, Rule, Text
from refpo_warp.utils.options import docs_for, option, rules_for

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


NOTICE_FIELDS = ("task", "algo", "num_envs", "env_steps", "actor_hidden_dims", "critic_hidden_dims")


def notice_text(template: str, cfg: dict, env_steps: int) -> str:
    """A run's notice with its own values filled in, so that a command-line override shows in it."""

    def dims(model: str) -> str:
        return " x ".join(str(d) for d in cfg.get(model, {}).get("hidden_dims") or []) or "-"

    return template.format(
        task=cfg["task"],
        algo=cfg["algo"],
        num_envs=cfg["num_envs"],
        env_steps=f"{env_steps:,}",
        actor_hidden_dims=dims("actor"),
        critic_hidden_dims=dims("critic"),
    )


def _check_notice(key: str, value: Any) -> str:
    if not isinstance(value, str):
        raise ConfigError(f"{key}={value!r} is invalid; expected a text")
    try:
        value.format(**dict.fromkeys(NOTICE_FIELDS, ""))
    except (KeyError, IndexError, ValueError) as err:
        raise ConfigError(
            f"{key}={value!r} is invalid ({type(err).__name__}: {err}); the fields filled in are "
            f"{', '.join('{' + f + '}' for f in NOTICE_FIELDS)} (write {{{{ and }}}} for literal braces)"
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


@dataclass(frozen=True)
class RunOptions:
    seed: int = option(rule=Int(0, 2**32 - 1), doc="seed of the run (numpy's seed range)")
    device: str = option(rule=Check(_check_device, "auto, cpu, cuda or cuda:N"), doc="where the run trains")
    num_envs: int = option(rule=Int(1, MAX_ENVS), doc="parallel envs")
    total_env_steps: int = option(rule=Int(1, 10**13), doc="env steps of the run (all envs together)")
    max_iterations: int | None = option(
        rule=Int(1, 10**8, optional=True), doc="iterations of the run; null: from total_env_steps"
    )
    run_dir: str | None = option(rule=Text(optional=True), doc="the run's folder; null: a new one under runs/")
    resume: bool = option(rule=Flag(), doc="train on from the run dir's last checkpoint")
    stop_after_iterations: int | None = option(
        rule=Int(1, 10**8, optional=True),
        doc="stop this call after that many iterations, at a checkpoint a resume continues bit for bit; null: never",
    )
    stop_after_minutes: float | None = option(
        rule=Real(0, 10**6, lo_open=True, optional=True),
        doc="stop this call at a checkpoint before that many minutes of training would pass; null: never",
    )
    verbose: bool = option(rule=Flag(), doc="print every iteration's statistics")
    # the run dir itself is checked when training starts (training/init_from.py)
    init_from: str | None = option(rule=Text(optional=True), doc="a run dir whose weights start this run")
    critic_warmup_iterations: int = option(rule=Int(0, 10**8), doc="iterations that train the critic alone first")
    clone_normalizer: str = option(
        rule=OneOf(("keep", "update")),
        doc="with init_from: the observation normalisers keep the data's statistics (as DPPO fine-tunes) or update",
    )
    # the folder itself is checked when the config path is built
    config_dir: str | None = option(rule=Text(optional=True), doc="a folder of config files that replaces configs/")
    notice: str | None = option(
        rule=Check(
            _check_notice, "null or a text ({task}, {algo}, {num_envs}, {env_steps}, ... filled in)", optional=True
        ),
        doc="a line printed when the run starts and ends, the run's values filled in for {task}, {algo}, "
        "{num_envs}, {env_steps}, {actor_hidden_dims} and {critic_hidden_dims}",
    )


@dataclass(frozen=True)
class RunnerOptions:
    num_steps_per_env: int = option(rule=Int(1, 1_000_000), doc="env steps per env and iteration (the rollout)")
    save_interval: int = option(rule=Int(1, 10**8), doc="iterations between checkpoints")
    logger: str = option(rule=Check(_check_logger, "tensorboard, wandb or neptune"), doc="where statistics go")
    check_for_nan: bool = option(rule=Flag(), doc="rsl_rl's check of the observations and rewards for NaN")
    # rsl_rl refuses the CUDA-graph modes "reduce-overhead" and "max-autotune"
    torch_compile_mode: str | None = option(
        rule=OneOf(None, "default", "max-autotune-no-cudagraphs"), doc="torch.compile's mode; null: not compiled"
    )
    obs_groups: dict = option(
        rule=Check(_check_obs_groups, "a mapping {set: [observation groups]}", fixed=True),
        doc="the observation groups each of actor and critic reads",
    )
    init_at_random_ep_len: bool = option(rule=Flag(), doc="start the envs at random points of their time-out")
    log_full: bool = option(rule=Flag(), doc="log every statistic rsl_rl has")


class DatasetActions(str, Enum):
    """What a demonstration dataset's actions are (``refpo_warp/demonstrations/dataset_actions.py``)."""

    AUTO = "auto"  # from the dataset: what refpo collect records, else its action space; unsure: refused
    PRE_SQUASH = "pre_squash"  # the policy's own actions (before the env's tanh): taken as they are
    ENV_UNITS = "env_units"  # what the env applied, in [-1, 1]: atanh on a tanh task


@dataclass(frozen=True)
class PretrainOptions:
    # read and checked by refpo pretrain (demonstrations/dataset_file.py)
    dataset: str | None = option(rule=Text(optional=True), doc="the demonstration file refpo pretrain reads")
    dataset_actions: str = option(
        rule=OneOf(DatasetActions),
        doc="what the dataset's actions are: pre_squash (the policy's, before a tanh env's squash: taken as they "
        "are), env_units (the env's, in [-1, 1]: atanh on a tanh task), auto (from the dataset; config.yaml keeps the "
        "choice)",
    )
    squash_margin: float = option(
        rule=Real(1e-12, 0.5), doc="env_units on a tanh task: |a| clipped to 1 - squash_margin before atanh"
    )
    epochs: int = option(rule=Int(1, 10**6), doc="passes over the demonstrations")
    batch_size: int = option(rule=Int(1, 1 << 24), doc="demonstrations per gradient step")
    learning_rate: float = option(rule=Real(0, 10, lo_open=True), doc="the pre-training learning rate")
    validation_fraction: float = option(
        rule=Real(0, 1, lo_open=True, hi_open=True), doc="share of the demonstrations held out"
    )
    patience: int = option(rule=Int(1, 10**6), doc="epochs without a better validation loss before it stops")
    num_pairs: int | None = option(rule=Int(1, 4096, optional=True), doc="(tau, eps) pairs per demonstration")


@dataclass(frozen=True)
class EvalOptions:
    at_end: bool = option(rule=Flag(), doc="evaluate the final policy")
    flow_steps: list[int] = option(rule=FLOW_STEPS, doc="flow-step counts N the final evaluation samples with")
    num_envs: int | None = option(rule=Int(1, MAX_ENVS, optional=True), doc="envs of the final evaluation")
    max_steps: int | None = option(rule=Int(1, 10**8, optional=True), doc="env steps of an evaluation")
    initial_noise: list[str] = option(rule=NOISE_PROTOCOLS_RULE, doc="initial-noise protocols evaluated")
    perturbation: bool = option(rule=Flag(), doc="evaluate with the actor's action perturbation")
    interval: int | None = option(rule=Int(0, 10**8, optional=True), doc="iterations between periodic evaluations")
    interval_flow_steps: list[int] = option(rule=FLOW_STEPS, doc="flow-step counts of the periodic evaluations")
    interval_num_envs: int = option(rule=Int(1, MAX_ENVS), doc="envs of the periodic evaluations")


SECTIONS = {"": RunOptions, "runner.": RunnerOptions, "pretrain.": PretrainOptions, "eval.": EvalOptions}
RUN_RULES: dict[str, Rule] = {f"{p}{k}": r for p, c in SECTIONS.items() for k, r in rules_for(c).items()}
RUN_DOCS: dict[str, str] = {f"{p}{k}": d for p, c in SECTIONS.items() for k, d in docs_for(c).items()}
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
