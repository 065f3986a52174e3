"""Evaluate a trained run: returns at several flow-step counts, flow diagnostics, ``eval.json`` and figures.

Flow policies are evaluated at every N in ``eval.flow_steps`` (1-step vs multi-step returns); a Gaussian actor
once, with its mean action. Task families may add a ``tasks/<family>/report.py`` with ``summarize(episodes)``
(extra numbers, e.g. GridWorld's top/bottom goal shares) and ``figures(run_dir, actor, cfg)`` (PNG files).
"""

from __future__ import annotations

import importlib
import json
import os
from pathlib import Path

import torch

from refpo_warp.evaluation import run_episodes, summarize
from refpo_warp.registry import get_task


def is_flow(actor) -> bool:
    return hasattr(actor, "num_flow_steps") and hasattr(actor, "velocity_error")


def family_report(task: str):
    """The task family's optional report module (``tasks.<family>.report``) or None."""
    family = get_task(task).entry_point.split(":")[0].rsplit(".", 1)[0]
    try:
        return importlib.import_module(f"{family}.report")
    except ModuleNotFoundError as err:
        if err.name != f"{family}.report":
            raise
        return None


def make_policy(actor, flow_steps: int | None, stochastic: bool):
    """obs -> actions for evaluation: a flow integrated with ``flow_steps`` Euler steps, or a Gaussian's mean."""
    if not is_flow(actor):
        return lambda obs: actor(obs)

    return lambda obs: actor(obs, stochastic_output=stochastic, num_steps=flow_steps)


def eval_num_envs(cfg: dict, interval: bool = False) -> int:
    """Evaluation env count: ``eval.num_envs``, or what the task's env class asks for when that is null."""
    n = cfg["eval"]["interval_num_envs" if interval else "num_envs"]
    if n:
        return int(n)
    env_class = get_task(cfg["task"]).env_class()
    from refpo_warp.registry import make_env_cfg

    env_cfg = make_env_cfg(cfg["task"], **{**cfg["env"], **cfg["eval"]["env"]})
    return int(env_class.eval_num_envs(env_cfg)) if hasattr(env_class, "eval_num_envs") else 64


def make_eval_env(cfg: dict, interval: bool = False):
    from refpo_warp.device import resolve_device
    from refpo_warp.registry import make_env

    return make_env(cfg["task"], num_envs=eval_num_envs(cfg, interval), device=resolve_device(cfg["device"]),
                    seed=cfg["seed"] + 10_000, **{**cfg["env"], **cfg["eval"]["env"]})  # fmt: skip


def evaluate_actor(cfg: dict, actor, env, flow_steps: list[int]) -> dict[str, dict]:
    """Summaries per evaluation setting: ``{"N=10": {...}, "N=1": {...}}`` (flows) or ``{"mean_action": {...}}``."""
    report = family_report(cfg["task"])
    settings = [(f"N={n}", n) for n in flow_steps] if is_flow(actor) else [("mean_action", None)]
    results = {}
    for name, n in settings:
        episodes = run_episodes(make_policy(actor, n, cfg["eval"]["stochastic"]), env,
                                max_steps=cfg["eval"]["max_steps"])  # fmt: skip
        summary = summarize(episodes)
        if report is not None and hasattr(report, "summarize"):
            summary.update(report.summarize(episodes))
        results[name] = summary
    return results


@torch.inference_mode()
def straightness_error(actor, env, num_pairs: int = 16) -> float:
    """MSE between v_theta and the straight direction a - eps on fresh pairs, for actions the policy samples."""
    obs = env.reset()
    actions = actor(obs, stochastic_output=True)
    tau = torch.rand(actions.shape[0], num_pairs, device=actions.device)
    eps = torch.randn(actions.shape[0], num_pairs, actions.shape[1], device=actions.device)
    return float(actor.velocity_error(obs, actions, tau, eps).mean())


def training_diagnostics(run_dir: Path) -> dict[str, float]:
    """Means of the per-update flow diagnostics logged during training (whole run and last 10% of iterations)."""
    from refpo_warp.plots import read_progress

    if not (run_dir / "progress.jsonl").exists():
        return {}
    rows = read_progress(run_dir)
    out: dict[str, float] = {}
    for key in ("straightness_error", "explosion_rate", "ratio_mean", "ratio_max", "clip_fraction"):
        values = [r[f"loss/{key}"] for r in rows if f"loss/{key}" in r]
        if values:
            tail = values[-max(1, len(values) // 10):]
            out[f"train_{key}"] = sum(values) / len(values)
            out[f"train_{key}_last10pct"] = sum(tail) / len(tail)
    return out


def write_json(data: dict, path: Path) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=2))
    os.replace(tmp, path)


def evaluate_run(run_dir: str | Path, cfg: dict | None = None, runner=None, checkpoint: str | Path | None = None,
                 overrides: dict | None = None) -> dict:  # fmt: skip
    """Evaluate a run's policy (the in-memory one, or a checkpoint) and write ``eval.json`` and the figures."""
    from refpo_warp.runner import latest_checkpoint
    from refpo_warp.training import build_runner, load_run_config

    run_dir = Path(run_dir)
    if cfg is None:
        cfg = load_run_config(run_dir, overrides or {})
    env = make_eval_env(cfg)
    if runner is None:
        checkpoint = Path(checkpoint) if checkpoint else latest_checkpoint(run_dir)
        if checkpoint is None:
            raise FileNotFoundError(f"No checkpoint (model_*.pt) in {run_dir}")
        _, runner = build_runner(cfg, None, env=env)
        runner.load(str(checkpoint), map_location=runner.device)
    actor = runner.get_inference_policy(device=runner.device)
    results = {
        "task": cfg["task"],
        "algo": cfg["algo"],
        "checkpoint_iteration": runner.current_learning_iteration,
        "eval_envs": env.num_envs,
        "stochastic": bool(cfg["eval"]["stochastic"]) if is_flow(actor) else False,
        "results": evaluate_actor(cfg, actor, env, cfg["eval"]["flow_steps"]),
    }
    diagnostics = training_diagnostics(run_dir)
    if is_flow(actor):
        diagnostics["straightness_error"] = straightness_error(actor, env)
        if "train_explosion_rate" in diagnostics:
            diagnostics["explosion_rate"] = diagnostics["train_explosion_rate"]
    results["diagnostics"] = diagnostics
    report = family_report(cfg["task"])
    if report is not None and hasattr(report, "figures"):
        results["figures"] = [str(p) for p in report.figures(run_dir, actor, cfg)]
    write_json(results, run_dir / "eval.json")
    runner.alg.train_mode()
    _print_results(results)
    return results


def _print_results(results: dict) -> None:
    for name, summary in results["results"].items():
        numbers = "  ".join(f"{k} {v:.4g}" for k, v in summary.items() if isinstance(v, float))
        print(f"[eval] {results['task']} {name}: {numbers}", flush=True)
    if results.get("diagnostics"):
        print("[eval] diagnostics: " + "  ".join(f"{k} {v:.4g}" for k, v in results["diagnostics"].items()))


def periodic_evaluator(cfg: dict, runner):
    """Hook for ``ProgressLogger.on_iteration``: every ``eval.interval`` iterations, returns at ``interval_flow_steps``."""
    env = make_eval_env(cfg, interval=True)
    interval = int(cfg["eval"]["interval"])

    def evaluate(it: int, is_last: bool) -> dict[str, float]:
        if (it + 1) % interval and not is_last:
            return {}
        actor = runner.alg.get_policy()
        was_training = actor.training
        actor.eval()
        results = evaluate_actor(cfg, actor, env, cfg["eval"]["interval_flow_steps"])
        actor.train(was_training)
        keys = {f"N={n}": f"eval/return_N{n}" for n in cfg["eval"]["interval_flow_steps"]}
        keys["mean_action"] = "eval/return"
        return {keys[name]: summary.get("return_mean", float("nan")) for name, summary in results.items()}

    return evaluate
