"""``refpo collect``: roll out a trained run's policy (any method, any task), or a task family's scripted demonstrator,
with optional Gaussian action noise, and write the episodes as a Minari dataset (``dataset_file``).

Every option (``collect_options.CollectOptions``) is checked and the policy loaded before the dataset is written; an
existing ``out`` is refused unless ``overwrite=true``. Env options (``env.<option>=``) apply over the env a run's
evaluation uses (its ``env`` options with ``eval.env`` over them: the policy rolled out without learning) or over the
task's defaults (a scripted demonstrator, which is built for the same env), each checked by the task's env cfg. The
dataset's metadata records the task, its env options (those set over the task's defaults), the observation groups and
the policy that made it (run dir, checkpoint, algorithm, flow steps, sampling, noise, seed), the env's
``action_transform`` and that the actions are the policy's own (``action_units: pre_squash``: before the env's tanh
where it squashes; ``dataset_actions``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import torch

from refpo_warp.config.saved import load_run
from refpo_warp.config.validate import env_section
from refpo_warp.demonstrations.collect_options import MAX_DEFAULT_ENVS, collect_options
from refpo_warp.demonstrations.dataset_actions import ACTION_TRANSFORM_KEY, ACTION_UNITS_KEY, PRE_SQUASH
from refpo_warp.demonstrations.dataset_file import write_dataset
from refpo_warp.demonstrations.rollout import collect_episodes
from refpo_warp.envs.registry import family_module, get_task, make_env, make_env_cfg
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import check_options
from refpo_warp.utils.options import declared_options, rules_for

COLLECT_SEED_OFFSET = 20_000  # collection envs draw other initial states than the run's training and evaluation


def collect(flat: dict[str, Any]) -> dict:
    """Collect and write the dataset; returns a summary (path, episodes, steps, returns, wall time)."""
    options, demo, env_given = collect_options(flat)
    device = resolve_device(options["device"])
    if options["run_dir"]:
        policy, env, groups, source, task, env_options = _run_policy(options, env_given, device)
    else:
        policy, env, groups, source, task, env_options = _scripted_policy(options, demo, env_given, device)
    generator = torch.Generator().manual_seed(env.seed)  # the action noise's own stream
    started = time.monotonic()
    print(
        f"[collect] {options['episodes']} episodes of {source['kind']} on {task} ({env.num_envs} envs, action "
        f"noise {options['noise']:g}) -> {options['out']}",
        flush=True,
    )
    episodes = collect_episodes(policy, env, options["episodes"], groups, options["noise"], generator)
    wall = time.monotonic() - started
    transform = getattr(env.cfg, "action_transform", "clip")
    action_bound = math.inf if transform == "tanh" else 1.0
    returns = [float(e.rewards.sum()) for e in episodes]
    refpo = {
        "task": task,
        "env": env_options,
        ACTION_TRANSFORM_KEY: transform,
        ACTION_UNITS_KEY: PRE_SQUASH,  # the policy's own actions (noise added), as the env received them before tanh
        "obs_groups": groups,
        "obs_group_dims": {g: int(env.get_observations()[g].shape[-1]) for g in groups},
        "policy": {**source, "initial_noise": options["initial_noise"], "action_noise_std": options["noise"]},
        "num_envs": env.num_envs,
        "collect_time_s": wall,
    }
    path = write_dataset(
        options["out"],
        episodes,
        episodes[0].observations.shape[-1],
        env.num_actions,
        action_bound,
        refpo,
        overwrite=options["overwrite"],
    )
    lengths = [e.length for e in episodes]
    return {
        "path": str(path),
        "episodes": len(episodes),
        "steps": sum(lengths),
        "wall_s": wall,
        "return_mean": sum(returns) / len(returns),
        "length_mean": sum(lengths) / len(lengths),
    }


def _num_envs(options: dict) -> int:
    return int(options["num_envs"] or min(options["episodes"], MAX_DEFAULT_ENVS))


def _run_policy(options: dict, env_given: dict, device: str):
    """The policy of a trained run (its newest usable checkpoint, or ``checkpoint``) and an env of its task: the env
    its evaluation rolls it out on (the run's ``env`` options, ``eval.env`` over them), with ``env_given`` over that
    (checked as a resumed run's: one that would change the policy's inputs or outputs is refused)."""
    from refpo_warp.evaluation.evaluate_policy import eval_env_options, is_flow
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    run_dir = Path(options["run_dir"])
    run = load_run(run_dir, {"device": device, **{f"env.{k}": v for k, v in env_given.items()}})
    cfg = run.cfg
    seed = options["seed"] if options["seed"] is not None else cfg["seed"] + COLLECT_SEED_OFFSET
    given = {key: cfg["env"][key] for key in env_given}  # as the run's config checked them
    env_options = {**eval_env_options(cfg), **given}
    env = make_env(run.task, num_envs=_num_envs(options), device=device, seed=seed, **env_options)
    _, runner = build_runner(run, None, env=env)
    if options["checkpoint"]:
        runner.load(options["checkpoint"], map_location=device)
        checkpoint = options["checkpoint"]
    else:
        checkpoint = str(load_latest(runner, run_dir, cfg["task"], cfg["algo"])[0])
    actor = runner.get_inference_policy(device=device)
    noise = options["initial_noise"]
    stochastic = noise == "random"
    if is_flow(actor):
        steps = options["flow_steps"] or actor.num_flow_steps

        def policy(obs):
            return actor.sample(obs, steps, noise, perturbation=False)
    else:
        steps = None

        def policy(obs):
            return actor(obs, stochastic_output=stochastic)

    torch.manual_seed(seed)  # the policy's own sampling noise
    source = {
        "kind": f"the policy of {run_dir}",
        "run_dir": str(run_dir.resolve()),
        "checkpoint": checkpoint,
        "algo": cfg["algo"],
        "actor_class": cfg["actor"]["class_name"],
        "flow_steps": steps,
        "iteration": runner.current_learning_iteration,
        "seed": seed,
    }
    return policy, env, list(cfg["runner"]["obs_groups"]["actor"]), source, cfg["task"], env_options


def _scripted_policy(options: dict, demo: dict, env_given: dict, device: str):
    """A task family's scripted demonstrator (``refpo_warp/tasks/<family>/demonstrator.py``) and an env of the task,
    both of the env options ``env_given`` over the task's defaults."""
    task = options["task"]
    env_options = _scripted_env_options(task, env_given)
    module = family_module(task, "demonstrator")
    if module is None:
        raise ConfigError(
            f"task={task} has no scripted demonstrator (tasks/<family>/demonstrator.py); collect from a "
            f"trained run with run_dir=..."
        )
    declared = declared_options(module.Options)  # the demonstrator module's option dataclass
    for key in demo:
        if key not in declared:
            raise unknown(f"option of {task}'s demonstrator (demonstrator.<option>)", key, list(declared))
    demo = {
        **{k: found.default for k, found in declared.items()},
        **check_options(rules_for(module.Options), demo, "demonstrator."),
    }
    seed = options["seed"] if options["seed"] is not None else 1
    env_cfg = make_env_cfg(task, **env_options)
    env = make_env(task, num_envs=_num_envs(options), device=device, seed=seed, **env_options)
    demonstrator = module.make_demonstrator(env_cfg, torch.Generator().manual_seed(seed), **demo)
    source = {**demonstrator.describe(), "kind": f"{task}'s scripted demonstrator", "algo": "scripted", "seed": seed}
    return demonstrator, env, ["policy"], source, task, env_options


def _scripted_env_options(task: str, given: dict) -> dict:
    """``given`` checked against ``task``'s env cfg (an option the task lacks names the task and its options), with
    the options a scripted demonstrator cannot take refused: the task's own settings (DMC's ``task``), and chunks."""
    spec = get_task(task)  # an unknown task id names the closest one
    options = env_section(spec, given)
    for key, value in options.items():
        if key in spec.cfg_overrides and value != spec.cfg_overrides[key]:
            raise ConfigError(f"env.{key}={value}: task={task} sets env.{key}={spec.cfg_overrides[key]}")
    if int(options.get("action_chunk", 1)) > 1:
        raise ConfigError(
            f"env.action_chunk={options['action_chunk']}: a scripted demonstrator acts one env step at a time; "
            "collect with env.action_chunk=1 (the default)"
        )
    return options
