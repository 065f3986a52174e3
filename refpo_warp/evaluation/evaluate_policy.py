"""Evaluate a policy on a vectorised env: returns and task metrics per evaluation setting, and the flow diagnostics
on the observations it visited.

Flow policies are evaluated at every N of a list of flow-step counts (1-step vs multi-step returns) under each
protocol of ``eval.initial_noise`` (random and / or zero initial noise x_0; ``setting_name``: ``N=10`` for random, the
paper's headline, ``N=10/zero`` for zero) and ``eval.perturbation`` (the rollout's post-sample noise on | off); a
Gaussian actor once, with its mean action. A task family may add ``refpo_warp/tasks/<family>/evaluation.py`` with
``summarize(episodes)`` (its own numbers, e.g. GridWorld's top/bottom goal shares), ``REPLACES`` (the generic
``<metric>_mean`` entries its numbers stand for, dropped so every metric has one name in ``eval.json``) and
``figures(run_dir, actor, cfg)`` (PNG files).

Evaluation during training (``periodic_evaluator``, between the runner's chunks: ``refpo_warp/training/train_run.py``):
every ``eval.interval`` iterations the returns at ``eval.interval_flow_steps`` under each ``eval.initial_noise``
protocol (``eval/return_N<n>``, ``eval/return_N<n>_zero``, or ``eval/return`` for a Gaussian actor), the means of the
env's ``curve_metrics`` beside them (``eval/success_N<n>``) and, for flows, the Jacobian statistics
(``Flow/jacobian_*``) on the visited observations. It draws from random streams of its own, seeded from the run's
seed and the iteration (``refpo_warp.utils.rng``), and reads the policy without updating its normaliser: a run
trains the same, bit for bit, with any ``eval.interval``.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import torch

from refpo_warp.config.resolve import Resolution
from refpo_warp.envs.registry import family_module, make_env, make_env_cfg
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.evaluation.episodes import run_episodes, summarize
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.rng import PERIODIC_EVALUATION, own_random_streams, stream_seed

EVAL_SEED_OFFSET = 10_000  # evaluation envs draw other initial states than the training envs of the same seed
RECORDED_OBSERVATIONS = 256  # visited observations the periodic evaluation keeps for the Jacobian statistics
Evaluator = Callable[[int, bool], dict[str, float]]  # (iteration, is_last) -> {name: value}


def is_flow(actor) -> bool:
    return hasattr(actor, "num_flow_steps") and hasattr(actor, "sample")


def family_evaluation(task: str | TaskSpec):
    """The task family's optional evaluation module (``refpo_warp.tasks.<family>.evaluation``) or None."""
    return family_module(task, "evaluation")


def setting_name(flow_steps: int, initial_noise: str = "random") -> str:
    """The key of one evaluation setting in ``eval.json``: ``N=10`` (random initial noise) or ``N=10/zero``."""
    return f"N={flow_steps}" if initial_noise == "random" else f"N={flow_steps}/{initial_noise}"


def curve_key(setting: str, metric: str = "return") -> str:
    """The progress-log key of a setting's periodic return (or of an env's curve metric): ``eval/return_N10``,
    ``eval/return_N10_zero``, ``eval/return`` (mean action), ``eval/success_N10``."""
    if not setting.startswith("N="):
        return f"eval/{metric}"
    return f"eval/{metric}_N" + setting[2:].replace("/", "_")


def make_policy(actor, flow_steps: int | None, initial_noise: str = "random", perturbation: bool = False):
    """obs -> actions for evaluation: a flow integrated with ``flow_steps`` Euler steps, or a Gaussian's mean."""
    if not is_flow(actor):
        return actor
    return lambda obs: actor.sample(obs, flow_steps, initial_noise, perturbation)


def eval_env_options(cfg: dict) -> dict:
    """The env options a run is evaluated with: its ``env`` options, ``eval.env``'s over them."""
    return {**cfg["env"], **cfg["eval"]["env"]}


def eval_num_envs(run: Resolution, interval: bool = False) -> int:
    """Evaluation env count: ``eval.num_envs``, or what the task's env class asks for when that is null."""
    cfg = run.cfg
    n = cfg["eval"]["interval_num_envs" if interval else "num_envs"]
    if n:
        return int(n)
    env_class = run.task.env_class()
    env_cfg = make_env_cfg(run.task, **eval_env_options(cfg))
    return int(env_class.eval_num_envs(env_cfg)) if hasattr(env_class, "eval_num_envs") else 64


def make_eval_env(run: Resolution, interval: bool = False) -> Any:
    """The evaluation env of a run's config (its ``eval.env`` options over ``env``)."""
    cfg = run.cfg
    return make_env(
        run.task,
        num_envs=eval_num_envs(run, interval),
        device=resolve_device(cfg["device"]),
        seed=cfg["seed"] + EVAL_SEED_OFFSET,
        **eval_env_options(cfg),
    )


def make_eval_envs(run: Resolution, interval: bool = False) -> dict[str, Any]:
    """One evaluation env per ``eval.initial_noise`` protocol, all from the same seed, so that a protocol's numbers
    (and the random stream that training shares with its periodic evaluation) do not depend on which other protocols
    are evaluated beside it."""
    return {noise: make_eval_env(run, interval) for noise in run.cfg["eval"]["initial_noise"]}


def evaluate_actor(
    run: Resolution, actor: Any, envs: Any, flow_steps: list[int], record_obs: int = 0
) -> tuple[dict[str, dict], Any]:
    """Summaries per evaluation setting (``{"N=10": {...}, "N=1": {...}, "N=10/zero": ...}`` for flows,
    ``{"mean_action": {...}}`` otherwise) and up to ``record_obs`` observations visited in the first setting (None if
    none were asked for). ``envs``: one env per protocol (``make_eval_envs``), or one env for all of them."""
    cfg, hooks = run.cfg, family_evaluation(run.task)
    protocols = cfg["eval"]["initial_noise"]
    envs = envs if isinstance(envs, dict) else dict.fromkeys(protocols, envs)
    settings: list[tuple[str, int | None, str]] = [("mean_action", None, protocols[0])]
    if is_flow(actor):
        settings = [(setting_name(n, noise), n, noise) for noise in protocols for n in flow_steps]
    results, visited = {}, None
    for name, n, noise in settings:
        policy = make_policy(actor, n, noise, cfg["eval"]["perturbation"])
        episodes = run_episodes(
            policy, envs[noise], max_steps=cfg["eval"]["max_steps"], record_obs=record_obs if visited is None else 0
        )
        visited = episodes.pop("observations", visited)
        summary = summarize(episodes)
        if hooks is not None and hasattr(hooks, "summarize"):
            for key in getattr(hooks, "REPLACES", ()):
                summary.pop(key, None)
            summary.update(hooks.summarize(episodes))
        results[name] = summary
    return results, visited


def periodic_evaluator(run: Resolution, runner: Any, envs: dict[str, Any] | None = None) -> Evaluator:
    """``evaluate(iteration, is_last) -> {name: value}`` for the iterations an evaluation is due at ({} otherwise);
    ``envs``: the evaluation envs (``make_eval_envs(run, interval=True)``, built here when not given)."""
    from refpo_warp.models.flow_diagnostics import jacobian_statistics

    cfg = run.cfg
    envs = envs if envs is not None else make_eval_envs(run, interval=True)
    interval = int(cfg["eval"]["interval"])

    def evaluate(it: int, is_last: bool) -> dict[str, float]:
        if (it + 1) % interval and not is_last:
            return {}
        actor = runner.alg.get_policy()
        was_training = actor.training
        actor.eval()
        flow = is_flow(actor)
        with own_random_streams(stream_seed(cfg["seed"], PERIODIC_EVALUATION, it), runner.device):
            results, visited = evaluate_actor(
                run, actor, envs, cfg["eval"]["interval_flow_steps"], record_obs=RECORDED_OBSERVATIONS if flow else 0
            )
            out = {curve_key(name): s.get("return_mean", float("nan")) for name, s in results.items()}
            for metric in next(iter(envs.values())).curve_metrics:
                out.update({curve_key(name, metric): s[f"{metric}_mean"] for name, s in results.items()})
            if flow and visited is not None and hasattr(actor, "velocity"):
                stats = jacobian_statistics(actor, visited, num_steps=actor.num_flow_steps)
                out.update({f"Flow/{k}": v for k, v in stats.items() if isinstance(v, float)})
        actor.train(was_training)
        return out

    return evaluate


def tau_sampler(alg):
    """Draws flow times the way ``alg`` draws its (tau, eps) pairs in training (uniform for algorithms without)."""
    from refpo_warp.algorithms.refpo import sample_tau

    if not hasattr(alg, "tau_sampling"):
        return partial(sample_tau, mode="uniform", num_flow_steps=1, logit_mean=0.0, logit_std=1.0, device="cpu")
    return partial(
        sample_tau,
        mode=alg.tau_sampling,
        num_flow_steps=alg.actor.num_flow_steps,
        logit_mean=alg.tau_logit_mean,
        logit_std=alg.tau_logit_std,
        device="cpu",
    )


def flow_diagnostics(alg, actor, observations, action_transform: str | None, seed: int) -> dict:
    """Straightness Error, one-step consistency (in the env's action space, from a random stream of its own seeded
    by ``seed``) and Jacobian statistics on on-policy observations, for the actors that define them."""
    from refpo_warp.models import flow_diagnostics as fd

    out: dict = {}
    if observations is None or not len(observations):
        return out
    if hasattr(actor, "cfm_terms"):
        out["straightness_error_eval"] = fd.straightness_error(actor, observations, tau_sampler(alg))
    if hasattr(actor, "velocity") and hasattr(actor.velocity, "project_obs"):
        generator = torch.Generator().manual_seed(seed)
        one_step = fd.one_step_consistency(
            actor, observations, actor.num_flow_steps, action_transform, generator=generator
        )
        out.update({f"{k}_eval": v for k, v in one_step.items()})
        out.update(fd.jacobian_statistics(actor, observations, num_steps=actor.num_flow_steps))
    return out
