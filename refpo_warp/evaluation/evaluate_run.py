"""Evaluate a run: its policy (in memory at the end of training, or a checkpoint) by ``evaluate_policy``, written to
``<run dir>/eval.json`` with the run's figures.

``eval.json`` holds the results per evaluation setting, the run's health (``refpo_warp.evaluation.run_health``: the
peak of each periodic evaluation curve, the final value and the drop between them, a cliff flagged) and, for flow
policies, diagnostics: the training-time means over the run of the per-update values logged in
``progress.jsonl`` (``straightness_error``, ``explosion_rate`` = the paper's "Explosion" / "Ratio Expl.",
``explosion_rate_pair``, ``clip_fraction``, ``one_step_error``, ``one_step_ratio``; ``ratio_max`` is the run's
maximum), and, on observations visited by the evaluated policy, ``straightness_error_eval``, the one-step consistency
(``one_step_error_eval``, ``policy_spread_eval``, ``one_step_ratio_eval``) and the Jacobian statistics
(``refpo_warp/models/flow_diagnostics.py``). ``machine`` records where it was written (``refpo_warp.utils.machine``):
at the end of ``refpo train``, the machine that trained the run's last piece (earlier pieces of a run trained in
pieces may have run elsewhere; ``train_time_s`` sums them all).
An existing ``eval.json`` is kept as ``eval.prev.json`` before the new one is written (both writes atomic).

The evaluation draws from random streams of its own, seeded from the run's seed and the checkpoint's iteration
(``refpo_warp.utils.rng``): the evaluation at the end of training and ``refpo eval`` of the same checkpoint give the
same numbers, and neither touches the streams of the process it runs in.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refpo_warp.config.resolve import Resolution
from refpo_warp.config.saved import load_run
from refpo_warp.evaluation import curves
from refpo_warp.evaluation.evaluate_policy import (
    evaluate_actor,
    family_evaluation,
    flow_diagnostics,
    is_flow,
    make_eval_envs,
)
from refpo_warp.evaluation.run_health import run_health
from refpo_warp.runner.build import build_runner, env_steps_per_iteration
from refpo_warp.runner.checkpoints import latest_checkpoint, load_latest
from refpo_warp.runner.progress import progress_path, read_rows
from refpo_warp.utils.atomic_files import write_json, write_text
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.machine import machine
from refpo_warp.utils.rng import FINAL_EVALUATION, own_random_streams, stream_seed

DIAGNOSTIC_OBSERVATIONS = 1024  # on-policy observations kept from the evaluation for the flow diagnostics
TRAINING_MEANS = (
    "straightness_error",
    "explosion_rate",
    "explosion_rate_pair",
    "clip_fraction",
    "one_step_error",
    "one_step_ratio",
)
EVAL_FILE, PREVIOUS_EVAL_FILE = "eval.json", "eval.prev.json"


def training_diagnostics(run_dir: Path) -> dict[str, float]:
    """Means over the run of the per-update flow diagnostics in ``progress.jsonl`` (``ratio_max``: the maximum)."""
    if not progress_path(run_dir).exists():
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


def write_eval_json(data: dict, run_dir: Path) -> Path | None:
    """Write ``eval.json``; an existing one is first copied to ``eval.prev.json`` (returned; None if there was none).

    A copy, not a rename: at every moment ``eval.json`` is a whole file, the old one or the new one.
    """
    path, previous = run_dir / EVAL_FILE, run_dir / PREVIOUS_EVAL_FILE
    kept = None
    if path.is_file():
        write_text(previous, path.read_text(encoding="utf-8", errors="replace"))
        kept = previous
    write_json(data, path)
    return kept


def evaluate_run(
    run_dir: str | Path,
    run: Resolution | None = None,
    runner: Any = None,
    checkpoint: str | Path | None = None,
    overrides: dict | None = None,
) -> dict:
    """Evaluate a run's policy (the in-memory one, or a checkpoint) and write ``eval.json`` and the figures.

    ``run``: the run's resolved config (training's), else the run dir's saved one with ``overrides``. Without
    ``checkpoint`` the newest usable checkpoint of the run is evaluated (newer unusable ones are skipped with a
    warning); a given ``checkpoint`` must be usable. Overrides may not change the run's task or model.
    """
    run_dir = Path(run_dir)
    if run is None:
        run = load_run(run_dir, overrides or {})
    cfg = run.cfg
    if runner is None and checkpoint is None and latest_checkpoint(run_dir) is None:
        raise ConfigError(f"run_dir={run_dir} holds no checkpoint (model_<iteration>.pt) to evaluate")
    envs = make_eval_envs(run)
    env = next(iter(envs.values()))
    if runner is None:
        _, runner = build_runner(run, None, env=env)
        if checkpoint is not None:
            runner.load(str(checkpoint), map_location=runner.device)
        else:
            load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device=runner.device)
    flow = is_flow(actor)
    iteration = runner.current_learning_iteration
    with own_random_streams(stream_seed(cfg["seed"], FINAL_EVALUATION, iteration), runner.device):
        results, visited = evaluate_actor(
            run, actor, envs, cfg["eval"]["flow_steps"], record_obs=DIAGNOSTIC_OBSERVATIONS if flow else 0
        )
        on_policy = flow_diagnostics(runner.alg, actor, visited, env.cfg.action_transform, cfg["seed"]) if flow else {}
    out = {
        "task": cfg["task"],
        "algo": cfg["algo"],
        "seed": cfg["seed"],
        "checkpoint_iteration": iteration,
        # the runner's count (every rank's env steps, as progress.jsonl); derived for checkpoints of other writers
        "env_steps": int(runner.logger.tot_timesteps) or (iteration + 1) * env_steps_per_iteration(cfg),
        "eval_envs": env.num_envs,
        "train_time_s": float(runner.logger.tot_time),
        "machine": machine(),
        "protocol": (
            {"initial_noise": cfg["eval"]["initial_noise"], "perturbation": bool(cfg["eval"]["perturbation"])}
            if flow
            else {"mean_action": True}
        ),
        "results": results,
        "health": run_health(read_rows(run_dir)) if progress_path(run_dir).exists() else {},
        "diagnostics": {**training_diagnostics(run_dir), **on_policy} if flow else {},
    }
    out["figures"] = [str(p) for p in run_figures(run_dir, actor, run)]
    kept = write_eval_json(out, run_dir)
    runner.alg.train_mode()
    if kept is not None:
        print(f"[eval] {run_dir / EVAL_FILE} replaced; the previous one is kept as {kept}", flush=True)
    return out


def run_figures(run_dir: Path, actor: Any, run: Resolution) -> list[Path]:
    """Every run's training curves (``curves.png``, and ``curves_diagnostics.png`` for flows) plus the task family's
    own figures."""
    cfg, figures = run.cfg, []
    if progress_path(run_dir).exists():
        rows = read_rows(run_dir)
        label = f"{cfg['task']} {cfg['algo']}"
        figures.append(curves.training_curves({label: rows}, run_dir / "curves.png"))
        if any(key in row for row in rows for key, _ in curves.DIAGNOSTICS):
            figures.append(curves.diagnostic_curves({label: rows}, run_dir / "curves_diagnostics.png"))
    hooks = family_evaluation(run.task)
    if hooks is not None and hasattr(hooks, "figures"):
        figures += hooks.figures(run_dir, actor, cfg)
    return figures
