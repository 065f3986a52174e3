"""The run options: every key of a run's config outside the class, env and video sections, declared like every other
option, a field ``option(default, rule, doc)`` (``refpo_warp/utils/options.py``) holding its one default. A section of
keys (``runner.*``) is a dataclass of its own, placed among the options by a ``section`` field; a section of another
class's options (``env``, ``actor``, ``critic``, ``algorithm``, ``video``, ``eval.env``) is a ``section`` field too,
empty here. ``run_defaults`` is the first layer of every run's config (``refpo_warp/config/layers.py``), in the order
the fields stand, which is the order of the keys of a saved ``config.yaml``. Also the checks that involve several
options.
"""

from __future__ import annotations

import copy
import dataclasses
import importlib.util
from dataclasses import dataclass
from enum import Enum
from typing import Any

from refpo_warp.models.sampled_policy import NOISE_PROTOCOLS_RULE, NUM_FLOW_STEPS
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_field import SECTION, section
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
class RunnerOptions:
    num_steps_per_env: int = option(24, Int(1, 1_000_000), "env steps per env and iteration (the rollout)")
    save_interval: int = option(50, Int(1, 10**8), "iterations between checkpoints (the final one is always written)")
    logger: str = option("tensorboard", Check(_check_logger, "tensorboard, wandb or neptune"), "where statistics go")
    check_for_nan: bool = option(True, Flag(), "rsl_rl's check of the observations and rewards for NaN")
    # rsl_rl refuses the CUDA-graph modes "reduce-overhead" and "max-autotune"
    torch_compile_mode: str | None = option(
        None, OneOf(None, "default", "max-autotune-no-cudagraphs"), "torch.compile's mode; null: not compiled"
    )
    obs_groups: dict = option(
        {"actor": ["policy"], "critic": ["policy"]},
        Check(_check_obs_groups, "a mapping {set: [observation groups]}", fixed=True),
        "the observation groups each of actor and critic reads",
    )
    init_at_random_ep_len: bool = option(False, Flag(), "start the envs at random points of their time-out")
    log_full: bool = option(False, Flag(), "print rsl_rl's full per-iteration report instead of one progress line")


class DatasetActions(str, Enum):
    """What a demonstration dataset's actions are (``refpo_warp/demonstrations/dataset_actions.py``)."""

    AUTO = "auto"  # from the dataset: what refpo collect records, else its action space; unsure: refused
    PRE_SQUASH = "pre_squash"  # the policy's own actions (before the env's tanh): taken as they are
    ENV_UNITS = "env_units"  # what the env applied, in [-1, 1]: atanh on a tanh task


@dataclass(frozen=True)
class PretrainOptions:
    """refpo pretrain's (behaviour cloning, docs/finetuning.md); refpo train ignores them."""

    # read and checked by refpo pretrain (demonstrations/dataset_file.py)
    dataset: str | None = option(
        None, Text(optional=True), "the demonstration file refpo pretrain reads (a Minari dataset folder)"
    )
    dataset_actions: str = option(
        DatasetActions.AUTO.value,
        OneOf(DatasetActions),
        "what the dataset's actions are: pre_squash (the policy's, before a tanh env's squash: taken as they "
        "are), env_units (the env's, in [-1, 1]: atanh on a tanh task), auto (from the dataset; config.yaml keeps the "
        "choice)",
    )
    squash_margin: float = option(
        1e-6, Real(1e-12, 0.5), "env_units on a tanh task: |a| clipped to 1 - squash_margin before atanh"
    )
    epochs: int = option(100, Int(1, 10**6), "passes over the demonstrations (at most; early stopping may end sooner)")
    batch_size: int = option(512, Int(1, 1 << 24), "demonstrations per gradient step")
    learning_rate: float = option(0.001, Real(0, 10, lo_open=True), "the pre-training learning rate (Adam)")
    validation_fraction: float = option(
        0.1, Real(0, 1, lo_open=True, hi_open=True), "share of the demonstrations held out"
    )
    patience: int = option(10, Int(1, 10**6), "epochs without a better validation loss before it stops")
    num_pairs: int | None = option(
        None,
        Int(1, 4096, optional=True),
        "flow actors: (tau, eps) pairs per demonstration; null: the algorithm's num_mc_samples (else 8)",
    )


@dataclass(frozen=True)
class EvalOptions:
    at_end: bool = option(True, Flag(), "evaluate the final policy (eval.json and figures in the run dir)")
    flow_steps: list[int] = option([1, 10, 20], FLOW_STEPS, "flow-step counts N the final evaluation samples with")
    num_envs: int | None = option(
        64, Int(1, MAX_ENVS, optional=True), "envs of the final evaluation; null: the task decides"
    )
    env: dict = section("env options of the evaluation envs only (e.g. the humanoid's eval mode)")
    max_steps: int | None = option(
        None, Int(1, 10**8, optional=True), "env steps of an evaluation; null: the env's max_episode_length"
    )
    initial_noise: list[str] = option(
        ["random"], NOISE_PROTOCOLS_RULE, "flow policies: initial-noise protocols evaluated (random or zero x_0)"
    )
    perturbation: bool = option(
        False, Flag(), "flow policies: evaluate with the actor's action perturbation (as the rollout samples)"
    )
    interval: int | None = option(
        None,
        Int(0, 10**8, optional=True),
        "iterations between periodic evaluations; null: 10 per run; 0: none",
    )
    interval_flow_steps: list[int] = option([10, 1], FLOW_STEPS, "flow-step counts of the periodic evaluations")
    interval_num_envs: int = option(16, Int(1, MAX_ENVS), "envs of the periodic evaluations")


@dataclass(frozen=True)
class RunOptions:
    """A run's config, every option at its place in config.yaml (a sweep compares saved files byte for byte)."""

    # checked by name against the registered tasks and the algo files (refpo_warp/config/config_set.py)
    task: str = option("gridworld", Text(), "the task id (refpo train --list-tasks)")
    algo: str = option("refpo", Text(), "the algorithm: a file configs/algo/<algo>.yaml")
    seed: int = option(1, Int(0, 2**32 - 1), "seed of the run (numpy's seed range)")
    device: str = option(
        "auto",
        Check(_check_device, "auto, cpu, cuda or cuda:N"),
        "where the run trains: auto (cuda:0 when available, else cpu), cpu or cuda:N",
    )
    torch_threads: int | None = option(
        None,
        Int(1, 1024, optional=True),
        "torch's CPU threads for the run's networks; null: 1 on a machine without CUDA (the env kernels and other runs "
        "share its cores), at most 4 with CUDA. More threads sum a matrix product in another order: the same run, "
        "other bits",
    )
    num_envs: int = option(64, Int(1, MAX_ENVS), "parallel envs")
    total_env_steps: int = option(
        1_000_000,
        Int(1, 10**13),
        "env steps of the run (all envs together): ceil(total_env_steps / (num_envs x runner.num_steps_per_env x "
        "env.action_chunk)) iterations",
    )
    max_iterations: int | None = option(
        None,
        Int(1, 10**8, optional=True),
        "iterations of the run (the budget in iterations); null: from total_env_steps",
    )
    run_dir: str | None = option(None, Text(optional=True), "the run's folder; null: runs/<task>/<algo>_seed<seed>")
    resume: bool = option(False, Flag(), "train on from the run dir's last checkpoint")
    stop_after_iterations: int | None = option(
        None,
        Int(1, 10**8, optional=True),
        "stop this call after that many iterations, at a checkpoint a resume continues bit for bit (a run in pieces, "
        "docs/cli.md); null: never",
    )
    stop_after_minutes: float | None = option(
        None,
        Real(0, 10**6, lo_open=True, optional=True),
        "stop this call at a checkpoint before that many minutes of training would pass; null: never",
    )
    verbose: bool = option(
        False, Flag(), "also print rsl_rl's messages: observation sets, model structure, git state of the code"
    )
    notice: str | None = option(
        None,
        Check(_check_notice, "a text ({task}, {algo}, {num_envs}, {env_steps}, ... filled in)", optional=True),
        "a line printed when the run starts and ends, the run's values filled in for {task}, {algo}, "
        "{num_envs}, {env_steps}, {actor_hidden_dims} and {critic_hidden_dims}",
    )
    env: dict = section("options of the task's env cfg (its dataclass in refpo_warp/tasks/<family>/cfg.py)")
    # the run dir itself is checked when training starts (training/init_from.py)
    init_from: str | None = option(
        None, Text(optional=True), "a refpo pretrain run dir whose cloned actor and normaliser start this run"
    )
    critic_warmup_iterations: int = option(
        10, Int(0, 10**8), "with init_from: the first iterations, in the budget, train the critic alone"
    )
    clone_normalizer: str = option(
        "keep",
        OneOf(("keep", "update")),
        "with init_from: the observation normalisers keep the data's statistics (as DPPO fine-tunes) or update",
    )
    # the folder itself is checked when the config path is built
    config_dir: str | None = option(
        None,
        Text(optional=True),
        "a folder of your own task/, algo/ and sweep/ files, searched before the shipped configs/ (docs/cli.md)",
    )
    runner: dict = section("rsl_rl's runner: the rollout, checkpoints, logging", RunnerOptions)
    actor: dict = section("the actor's class_name and its options (configs/algo/<algo>.yaml)")
    critic: dict = section("the critic's class_name and its options (configs/algo/<algo>.yaml)")
    algorithm: dict = section("the algorithm's class_name and its options (configs/algo/<algo>.yaml)")
    video: dict = section("videos of the policy during and after training (refpo_warp/render/options.py)")
    pretrain: dict = section("refpo pretrain's options (behaviour cloning); refpo train ignores them", PretrainOptions)
    eval: dict = section("the evaluation after training and during it", EvalOptions)


def _sections(options: type, prefix: str = "") -> dict[str, type | None]:
    """Every section of ``options``, by dotted prefix (``""``: the top), and the dataclass of its options (None: the
    options of another class, which declares and checks them)."""
    out: dict[str, type | None] = {prefix: options}
    for f in dataclasses.fields(options):
        if SECTION in f.metadata:
            inner = f.metadata[SECTION]
            out.update(_sections(inner, f"{prefix}{f.name}.") if inner is not None else {f"{prefix}{f.name}": None})
    return out


def _defaults(options: type) -> dict:
    out: dict = {}
    for f in dataclasses.fields(options):
        if SECTION in f.metadata:
            inner = f.metadata[SECTION]
            out[f.name] = _defaults(inner) if inner is not None else {}
        else:
            out[f.name] = copy.deepcopy(
                f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
            )
    return out


def run_defaults() -> dict:
    """Every run option's default, nested by section and in config.yaml's order; the sections of other classes'
    options (``env``, ``actor``, ``critic``, ``algorithm``, ``video``, ``eval.env``) empty."""
    return _defaults(RunOptions)


SECTIONS = {p: c for p, c in _sections(RunOptions).items() if c is not None}
RUN_RULES: dict[str, Rule] = {f"{p}{k}": r for p, c in SECTIONS.items() for k, r in rules_for(c).items()}
RUN_DOCS: dict[str, str] = {f"{p}{k}": d for p, c in SECTIONS.items() for k, d in docs_for(c).items()}
# The sections that other classes declare and check: env and eval.env (the task's env cfg), actor, critic and
# algorithm (their classes), video (VideoOptions).
NOT_RULED = tuple(p for p, c in _sections(RunOptions).items() if c is None)


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
