"""Evaluate a trained run: returns at several flow-step counts, flow diagnostics, ``eval.json`` and figures.

Flow policies are evaluated at every N in ``eval.flow_steps`` (1-step vs multi-step returns) under the protocol
``eval.initial_noise`` (random | zero) and ``eval.perturbation`` (the rollout's post-sample noise on | off); a
Gaussian actor once, with its mean action. Task families may add a ``tasks/<family>/report.py`` with
``summarize(episodes)`` (their own numbers, e.g. GridWorld's top/bottom goal shares), ``REPLACES`` (the generic
``<metric>_mean`` entries their numbers stand for, dropped so every metric has one name in ``eval.json``) and
``figures(run_dir, actor, cfg)`` (PNG files).

An existing ``eval.json`` is kept as ``eval.prev.json`` before the new one is written (both writes atomic).

``eval.json`` diagnostics of flow policies: the training-time means over the run of the per-update values logged in
``progress.jsonl`` (``straightness_error``, ``explosion_rate`` = the paper's "Explosion" / "Ratio Expl.",
``explosion_rate_pair``, ``clip_fraction``; ``ratio_max`` is the run's maximum), and, on observations visited by
the evaluated policy, ``straightness_error_eval`` and the Jacobian statistics (``refpo_warp.models.flow_diagnostics``).
"""

from __future__ import annotations

import importlib
import json
from functools import partial
from pathlib import Path

from refpo_warp.envs.registry import get_task
from refpo_warp.evaluation.episodes import run_episodes, summarize

DIAGNOSTIC_OBSERVATIONS = 1024  # on-policy observations kept from the evaluation for the flow diagnostics
TRAINING_MEANS = ("straightness_error", "explosion_rate", "explosion_rate_pair", "clip_fraction")


def is_flow(actor) -> bool:
    return hasattr(actor, "num_flow_steps") and hasattr(actor, "sample")


def family_report(task: str):
    """The task family's optional evaluation module (``refpo_warp.tasks.<family>.evaluation``) or None."""
    family = get_task(task).entry_point.split(":")[0].rsplit(".", 1)[0]
    try:
        return importlib.import_module(f"{family}.evaluation")
    except ModuleNotFoundError as err:
        if err.name != f"{family}.evaluation":
            raise
        return None


def make_policy(actor, flow_steps: int | None, initial_noise: str = "random", perturbation: bool = False):
    """obs -> actions for evaluation: a flow integrated with ``flow_steps`` Euler steps, or a Gaussian's mean."""
    if not is_flow(actor):
        return lambda obs: actor(obs)
    return lambda obs: actor.sample(obs, flow_steps, initial_noise, perturbation)


def eval_num_envs(cfg: dict, interval: bool = False) -> int:
    """Evaluation env count: ``eval.num_envs``, or what the task's env class asks for when that is null."""
    n = cfg["eval"]["interval_num_envs" if interval else "num_envs"]
    if n:
        return int(n)
    env_class = get_task(cfg["task"]).env_class()
    from refpo_warp.envs.registry import make_env_cfg

    env_cfg = make_env_cfg(cfg["task"], **{**cfg["env"], **cfg["eval"]["env"]})
    return int(env_class.eval_num_envs(env_cfg)) if hasattr(env_class, "eval_num_envs") else 64


def make_eval_env(cfg: dict, interval: bool = False):
    from refpo_warp.envs.registry import make_env
    from refpo_warp.utils.device import resolve_device

    return make_env(cfg["task"], num_envs=eval_num_envs(cfg, interval), device=resolve_device(cfg["device"]),
                    seed=cfg["seed"] + 10_000, **{**cfg["env"], **cfg["eval"]["env"]})  # fmt: skip


def evaluate_actor(cfg: dict, actor, env, flow_steps: list[int], record_obs: int = 0) -> tuple[dict, object]:
    """Summaries per evaluation setting (``{"N=10": {...}, "N=1": {...}}`` for flows, ``{"mean_action": {...}}``
    otherwise) and up to ``record_obs`` observations visited in the first setting (None if none were asked for)."""
    report = family_report(cfg["task"])
    settings = [(f"N={n}", n) for n in flow_steps] if is_flow(actor) else [("mean_action", None)]
    results, visited = {}, None
    for name, n in settings:
        policy = make_policy(actor, n, cfg["eval"]["initial_noise"], cfg["eval"]["perturbation"])
        episodes = run_episodes(policy, env, max_steps=cfg["eval"]["max_steps"],
                                record_obs=record_obs if visited is None else 0)  # fmt: skip
        visited = episodes.pop("observations", visited)
        summary = summarize(episodes)
        if report is not None and hasattr(report, "summarize"):
            for key in getattr(report, "REPLACES", ()):
                summary.pop(key, None)
            summary.update(report.summarize(episodes))
        results[name] = summary
    return results, visited


def tau_sampler(cfg: dict, actor):
    """Draws flow times the way the run's algorithm drew them in training (uniform for algorithms without pairs)."""
    from refpo_warp.algorithms.refpo import sample_tau

    alg = cfg["algorithm"]
    return partial(sample_tau, mode=alg.get("tau_sampling", "uniform"), num_flow_steps=actor.num_flow_steps,
                   logit_mean=alg.get("tau_logit_mean", -1.2), logit_std=alg.get("tau_logit_std", 1.2),
                   device="cpu")  # fmt: skip


def flow_diagnostics(cfg: dict, actor, observations) -> dict:
    """Straightness Error and Jacobian statistics on on-policy observations (for actors that define them)."""
    from refpo_warp.models import flow_diagnostics as fd

    out: dict = {}
    if observations is None or not len(observations):
        return out
    if hasattr(actor, "cfm_terms"):
        out["straightness_error_eval"] = fd.straightness_error(actor, observations, tau_sampler(cfg, actor))
    if hasattr(actor, "velocity") and hasattr(actor.velocity, "project_obs"):
        out.update(fd.jacobian_statistics(actor, observations, num_steps=actor.num_flow_steps))
    return out


def training_diagnostics(run_dir: Path) -> dict[str, float]:
    """Means over the run of the per-update flow diagnostics in ``progress.jsonl`` (``ratio_max``: the maximum)."""
    from refpo_warp.runner.progress import read_rows

    if not (run_dir / "progress.jsonl").exists():
        return {}
    rows = read_rows(run_dir)
    out: dict[str, float] = {}
    for key in TRAINING_MEANS:
        values = [r[f"Flow/{key}"] for r in rows if f"Flow/{key}" in r]
        if values:
            out[key] = sum(values) / len(values)
    ratio_max = [r["Flow/ratio_max"] for r in rows if "Flow/ratio_max" in r]
    if ratio_max:
        out["ratio_max"] = max(ratio_max)
    return out


EVAL_FILE, PREVIOUS_EVAL_FILE = "eval.json", "eval.prev.json"


def write_json(data: dict, path: Path) -> None:
    from refpo_warp.utils.atomic_files import write_text

    write_text(path, json.dumps(data, indent=2))


def write_eval_json(data: dict, run_dir: Path) -> Path | None:
    """Write ``eval.json``; an existing one is first copied to ``eval.prev.json`` (returned; None if there was none).

    A copy, not a rename: at every moment ``eval.json`` is a whole file, the old one or the new one.
    """
    from refpo_warp.utils.atomic_files import write_text

    path, previous = run_dir / EVAL_FILE, run_dir / PREVIOUS_EVAL_FILE
    kept = None
    if path.is_file():
        write_text(previous, path.read_text(encoding="utf-8", errors="replace"))
        kept = previous
    write_json(data, path)
    return kept


def evaluate_run(run_dir: str | Path, cfg: dict | None = None, runner=None, checkpoint: str | Path | None = None,
                 overrides: dict | None = None) -> dict:  # fmt: skip
    """Evaluate a run's policy (the in-memory one, or a checkpoint) and write ``eval.json`` and the figures.

    Without ``checkpoint`` the newest usable checkpoint of the run is evaluated (newer unusable ones are skipped
    with a warning); a given ``checkpoint`` must be usable. Overrides may not change the run's task or model.
    """
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import latest_checkpoint, load_latest
    from refpo_warp.runner.run_dir import load_run_config
    from refpo_warp.utils.errors import ConfigError

    run_dir = Path(run_dir)
    if cfg is None:
        cfg = load_run_config(run_dir, overrides or {})
    if runner is None and checkpoint is None and latest_checkpoint(run_dir) is None:
        raise ConfigError(f"run_dir={run_dir} holds no checkpoint (model_<iteration>.pt) to evaluate")
    env = make_eval_env(cfg)
    if runner is None:
        _, runner = build_runner(cfg, None, env=env)
        if checkpoint is not None:
            runner.load(str(checkpoint), map_location=runner.device)
        else:
            load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device=runner.device)
    flow = is_flow(actor)
    results, visited = evaluate_actor(cfg, actor, env, cfg["eval"]["flow_steps"],
                                      record_obs=DIAGNOSTIC_OBSERVATIONS if flow else 0)  # fmt: skip
    out = {
        "task": cfg["task"],
        "algo": cfg["algo"],
        "seed": cfg["seed"],
        "checkpoint_iteration": runner.current_learning_iteration,
        "env_steps": ((runner.current_learning_iteration + 1) * cfg["num_envs"] * cfg["runner"]["num_steps_per_env"]
                      * cfg["env"].get("action_chunk", 1)),  # a policy step of an action-chunk env is H env steps
        "eval_envs": env.num_envs,
        "protocol": ({"initial_noise": cfg["eval"]["initial_noise"], "perturbation": bool(cfg["eval"]["perturbation"])}
                     if flow else {"mean_action": True}),  # fmt: skip
        "results": results,
        "diagnostics": {**training_diagnostics(run_dir), **flow_diagnostics(cfg, actor, visited)} if flow else {},
    }
    out["figures"] = [str(p) for p in run_figures(run_dir, actor, cfg)]
    kept = write_eval_json(out, run_dir)
    runner.alg.train_mode()
    if kept is not None:
        print(f"[eval] {run_dir / EVAL_FILE} replaced; the previous one is kept as {kept}", flush=True)
    return out


def run_figures(run_dir: Path, actor, cfg: dict) -> list[Path]:
    """Every run's training curves (``curves.png``, and ``curves_diagnostics.png`` for flows) plus the task family's
    own figures."""
    from refpo_warp.evaluation import curves
    from refpo_warp.runner.progress import read_rows

    figures = []
    if (run_dir / "progress.jsonl").exists():
        rows = read_rows(run_dir)
        label = f"{cfg['task']} {cfg['algo']}"
        figures.append(curves.training_curves({label: rows}, run_dir / "curves.png"))
        if any(key in row for row in rows for key, _ in curves.DIAGNOSTICS):
            figures.append(curves.diagnostic_curves({label: rows}, run_dir / "curves_diagnostics.png"))
    report = family_report(cfg["task"])
    if report is not None and hasattr(report, "figures"):
        figures += report.figures(run_dir, actor, cfg)
    return figures


def periodic_evaluator(cfg: dict, runner):
    """Evaluation between training chunks (``refpo_warp.training``): every ``eval.interval`` iterations, the returns at
    ``eval.interval_flow_steps`` (``eval/return_N<n>``, or ``eval/return`` for a Gaussian actor) and, for flows,
    the Jacobian statistics (``Flow/jacobian_*``) on the visited observations."""
    env = make_eval_env(cfg, interval=True)
    interval = int(cfg["eval"]["interval"])

    def evaluate(it: int, is_last: bool) -> dict[str, float]:
        if (it + 1) % interval and not is_last:
            return {}
        actor = runner.alg.get_policy()
        was_training = actor.training
        actor.eval()
        flow = is_flow(actor)
        results, visited = evaluate_actor(cfg, actor, env, cfg["eval"]["interval_flow_steps"],
                                          record_obs=256 if flow else 0)  # fmt: skip
        out = {f"eval/return_N{name[2:]}" if name.startswith("N=") else "eval/return": s.get("return_mean", float("nan"))
               for name, s in results.items()}  # fmt: skip
        if flow and visited is not None and hasattr(actor, "velocity"):
            from refpo_warp.models.flow_diagnostics import jacobian_statistics

            stats = jacobian_statistics(actor, visited, num_steps=actor.num_flow_steps)
            out.update({f"Flow/{k}": v for k, v in stats.items() if isinstance(v, float)})
        actor.train(was_training)
        return out

    return evaluate
