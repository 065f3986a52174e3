"""``refpo pretrain``: clone the actor an algorithm uses from a demonstration dataset, evaluate it and save it as a
checkpoint in rsl_rl's layout (``model_0.pt``: actor, critic and optimizer states, ``iter``), so that
``refpo train init_from=<this run dir>`` fine-tunes it and a plain rsl_rl ``OnPolicyRunner.load()`` reads it.

Order of work, as ``refpo train``: the config, the run dir and the whole dataset (format, spaces, values, episode
ends, what its actions are: ``dataset_actions``) are checked and the model built before anything is written; a
refused run leaves the disk as it was.

The run dir holds ``config.yaml`` (the resolved config with its ``pretrain`` section, ``pretrain.dataset_actions``
being what the actions were taken as: ``auto`` is replaced by its decision), ``model_0.pt``,
``progress.jsonl`` (one row per epoch: training and validation loss), TensorBoard events, ``eval.json`` (the cloned
policy at every ``eval.flow_steps`` N for a flow, the mean action for a Gaussian) and the task's figures.
"""

from __future__ import annotations

import contextlib
import json
import time
from pathlib import Path
from typing import Any

import torch

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.config.resolve import Resolution, resolve
from refpo_warp.config.saved import RUN_CONFIG
from refpo_warp.config.yaml_files import dump_config
from refpo_warp.demonstrations.behaviour_cloning import (
    CloneOptions,
    check_clonable,
    clone,
    is_flow_actor,
    make_loss,
    set_normalizer,
    split_episodes,
)
from refpo_warp.demonstrations.dataset_actions import ActionUnits, action_units, squashes
from refpo_warp.demonstrations.dataset_file import check_spaces, env_differences, read_dataset
from refpo_warp.evaluation.evaluate_policy import (
    eval_env_options,
    evaluate_actor,
    family_evaluation,
    make_eval_envs,
    tau_sampler,
)
from refpo_warp.evaluation.evaluate_run import write_eval_json
from refpo_warp.runner.build import build_runner, seed_everything
from refpo_warp.runner.checkpoints import META_KEY, latest_checkpoint
from refpo_warp.runner.progress import progress_path
from refpo_warp.runner.run_dir import check_new_run_dir, check_writable, run_lock
from refpo_warp.utils.atomic_files import append_line, atomic_write, remove_stale_temp_files
from refpo_warp.utils.errors import ConfigError, tag_run_dir
from refpo_warp.utils.rng import FINAL_EVALUATION, own_random_streams, stream_seed
from refpo_warp.utils.rsl_rl_versions import uncompiled

CHECKPOINT = "model_0.pt"  # iteration 0 of the fine-tuning that starts from it


def default_pretrain_dir(task: str, algo: str, seed: int) -> Path:
    return Path("runs") / task / f"pretrain_{algo}_seed{seed}"


def pretrain_config(options: list[str] | dict[str, Any]) -> Resolution:
    """The resolved config of a pretrain run and its task's spec (``dataset=`` is ``pretrain.dataset``)."""
    flat = parse_overrides(options) if isinstance(options, list) else dict(options)
    if "dataset" in flat:
        if "pretrain.dataset" in flat:
            raise ConfigError("dataset= and pretrain.dataset= name the same option; give one")
        flat["pretrain.dataset"] = flat.pop("dataset")
    for key in ("resume", "init_from"):
        if flat.get(key):
            raise ConfigError(f"{key}= is an option of refpo train; refpo pretrain starts a new run each time")
    run = resolve(flat)
    cfg = run.cfg
    if not cfg["pretrain"]["dataset"]:
        raise ConfigError("refpo pretrain needs dataset=PATH (a Minari dataset folder; refpo collect writes one)")
    cfg["run_dir"] = str(cfg["run_dir"] or default_pretrain_dir(cfg["task"], cfg["algo"], cfg["seed"]))
    return run


def pretrain(options: list[str] | dict[str, Any]) -> dict:
    """Clone, evaluate and save; returns the evaluation (as written to ``eval.json``) with the cloning summary."""
    run = pretrain_config(options)
    cfg = run.cfg
    run_dir = Path(cfg["run_dir"])
    check_writable(run_dir)
    if run_dir.is_dir() and latest_checkpoint(run_dir) is not None:
        raise ConfigError(f"{run_dir} already holds checkpoints; choose another run_dir for a new pretrain run")
    check_new_run_dir(run_dir)
    dataset = read_dataset(cfg["pretrain"]["dataset"])
    seed_everything(cfg["seed"])
    env, runner = build_runner(run, None)
    actor = uncompiled(runner.alg, "actor")
    check_clonable(actor, cfg["algo"])
    groups = {g: int(env.get_observations()[g].shape[-1]) for g in cfg["runner"]["obs_groups"]["actor"]}
    check_spaces(dataset, cfg["task"], sum(groups.values()), env.num_actions)
    differences = env_differences(dataset, cfg["task"], eval_env_options(cfg))
    if differences:  # allowed (a clone may be meant for another env), but said: a mistake here is easy to miss
        print(f"[pretrain] note: the dataset's env is not the one the clone is evaluated on: {'; '.join(differences)}")
    p = cfg["pretrain"]
    units = action_units(dataset, p["dataset_actions"], squashes(env), p["squash_margin"], cfg["task"])
    p["dataset_actions"] = units.units  # config.yaml holds what the actions were taken as (auto: what it decided)
    train_ids, val_ids = split_episodes(len(dataset.episodes), p["validation_fraction"], cfg["seed"])
    train_data, val_data = (_training_pairs(dataset, ids, units) for ids in (train_ids, val_ids))
    # --- everything below writes; everything above could refuse the run without touching the disk
    run_dir.mkdir(parents=True, exist_ok=True)
    with run_lock(run_dir), tag_run_dir(run_dir):
        remove_stale_temp_files(run_dir)
        for stale in (progress_path(run_dir), run_dir / "eval.json", run_dir / "eval.prev.json"):
            stale.unlink(missing_ok=True)
        dump_config(cfg, run_dir / RUN_CONFIG)
        return _clone_and_evaluate(run, runner, actor, groups, dataset, units, train_data, val_data, run_dir)


def _training_pairs(dataset: Any, episode_ids: list[int], units: ActionUnits) -> tuple[Any, Any]:
    """(observations, actions) of the chosen episodes, the actions as the clone's policy outputs them."""
    obs, actions = dataset.transitions(episode_ids)
    return obs, units.apply(actions)


def _clone_and_evaluate(
    run: Resolution,
    runner: Any,
    actor: Any,
    groups: dict[str, int],
    dataset: Any,
    units: ActionUnits,
    train_data: Any,
    val_data: Any,
    run_dir: Path,
) -> dict:
    cfg = run.cfg
    p = cfg["pretrain"]
    normalised = set_normalizer(actor, train_data[0])
    if cfg["runner"]["obs_groups"]["critic"] == cfg["runner"]["obs_groups"]["actor"]:
        set_normalizer(uncompiled(runner.alg, "critic"), train_data[0])  # the critic's warm-up starts from the data's
    for param in _normalizer_parameters(actor):
        param.requires_grad_(False)
    alg = runner.alg
    num_pairs = p["num_pairs"] or int(getattr(alg, "num_mc_samples", 8))
    loss = make_loss(actor, tau_sampler(alg), num_pairs)
    kind = "flow (CFM loss)" if is_flow_actor(actor) else "Gaussian (max. likelihood)"
    print(
        f"[pretrain] {cfg['task']} / {cfg['algo']}: cloning the {kind} actor from {dataset.path} "
        f"({len(dataset.episodes)} episodes, {len(train_data[0]):,} training and {len(val_data[0]):,} validation "
        f"transitions; observation normaliser {'from the data' if normalised else 'off'}; actions: "
        f"{units.describe()}), at most {p['epochs']} epochs, run dir {run_dir}",
        flush=True,
    )
    writer = _tensorboard(run_dir)

    def report(row: dict) -> None:
        # "iteration" is the epoch, so the run's tools (refpo eval, refpo plot) read the file as any progress log
        append_line(progress_path(run_dir), json.dumps({"iteration": row["epoch"], **row}))
        if writer is not None:
            writer.add_scalar("BC/train_loss", row["train_loss"], row["epoch"])
            writer.add_scalar("BC/val_loss", row["val_loss"], row["epoch"])
        print(
            f"[epoch {row['epoch']}/{p['epochs'] - 1}] train {row['train_loss']:.4f}  validation "
            f"{row['val_loss']:.4f} (best {row['best_val_loss']:.4f})  {row['time_s']:.0f} s",
            flush=True,
        )

    options = CloneOptions(p["epochs"], p["batch_size"], p["learning_rate"], p["patience"], num_pairs, cfg["seed"])
    summary = {**clone(actor, loss, groups, train_data, val_data, options, report), **units.summary()}
    print(
        f"[pretrain] best validation loss {summary['best_val_loss']:.4f} at epoch {summary['best_epoch']} "
        f"({summary['epochs_run']} epochs, {summary['time_s']:.0f} s)",
        flush=True,
    )
    checkpoint = save_checkpoint(runner, cfg, run_dir / CHECKPOINT, {**summary, "dataset": str(dataset.path)})
    results = evaluate_clone(run, runner, actor, run_dir, summary, dataset)
    if writer is not None:
        for setting, numbers in results["results"].items():
            for key, value in numbers.items():
                if isinstance(value, float):
                    writer.add_scalar(f"Eval/{setting}/{key}", value, 0)
        writer.close()
    results["checkpoint"] = str(checkpoint)
    return results


def _normalizer_parameters(actor):
    return [p for name, p in actor.named_parameters() if "normalizer" in name]


def _tensorboard(run_dir: Path):
    with contextlib.suppress(ImportError):
        from torch.utils.tensorboard import SummaryWriter

        return SummaryWriter(log_dir=str(run_dir), flush_secs=10)
    return None


def save_checkpoint(runner, cfg: dict, path: Path, pretrain: dict) -> Path:
    """The cloned models in rsl_rl's checkpoint layout, written atomically; ``refpo_warp`` metadata as training's."""
    saved = runner.alg.save()
    saved["iter"] = 0
    saved["infos"] = None
    saved[META_KEY] = {
        "task": cfg["task"],
        "algo": cfg["algo"],
        "env_steps": 0,
        "time_s": 0.0,
        "pretrain": {k: v for k, v in pretrain.items() if isinstance(v, (int, float, str, bool))},
    }
    with atomic_write(path) as f:
        torch.save(saved, f)
    return path


def evaluate_clone(run: Resolution, runner: Any, actor: Any, run_dir: Path, summary: dict, dataset: Any) -> dict:
    """The cloned policy's evaluation (the run's protocol, streams of its own) written to ``eval.json``, with the
    dataset's own success numbers beside it where the task defines them, and the task's figures."""
    cfg, started = run.cfg, time.monotonic()
    actor.eval()
    with own_random_streams(stream_seed(cfg["seed"], FINAL_EVALUATION, 0), runner.device), torch.inference_mode():
        results, _ = evaluate_actor(run, actor, make_eval_envs(run), list(cfg["eval"]["flow_steps"]))
    lengths = [e.length for e in dataset.episodes]
    out = {
        "task": cfg["task"],
        "algo": cfg["algo"],
        "seed": cfg["seed"],
        "checkpoint_iteration": 0,
        "env_steps": 0,
        "kind": "behaviour cloning",
        "pretrain": summary,
        "dataset": {
            "path": str(dataset.path),
            "episodes": len(lengths),
            "steps": sum(lengths),
            "return_mean": sum(float(e.rewards.sum()) for e in dataset.episodes) / len(lengths),
            "length_mean": sum(lengths) / len(lengths),
            "policy": dataset.refpo.get("policy", {}),
        },
        "protocol": (
            {"initial_noise": cfg["eval"]["initial_noise"], "perturbation": bool(cfg["eval"]["perturbation"])}
            if is_flow_actor(actor)
            else {"mean_action": True}
        ),
        "results": results,
    }
    hooks = family_evaluation(run.task)
    if hooks is not None and hasattr(hooks, "dataset_summary"):
        out["dataset"].update(hooks.dataset_summary(dataset))
    if hooks is not None and hasattr(hooks, "figures"):
        out["figures"] = [str(p) for p in hooks.figures(run_dir, actor, cfg)]
    out["eval_time_s"] = time.monotonic() - started
    write_eval_json(out, run_dir)
    return out
