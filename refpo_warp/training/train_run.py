"""Train a policy from a resolved config: the implementation behind ``refpo train``.

``train(["task=gridworld", "algo=refpo", "seed=1"])`` builds the env and rsl_rl's runner (extended in
``refpo_warp.runner.runner``), writes the resolved config next to the checkpoints, trains (or resumes), evaluates at the
end and returns the evaluation results (also written to ``eval.json`` in the run dir).

Order of work: everything that can refuse a run (options, run dir, resume compatibility, env, runner, checkpoint)
happens before the first byte is written, so a refused run leaves the disk as it was.

Under torchrun every rank trains on its own device (``cuda:LOCAL_RANK``, or the CPU) with seed ``seed + RANK``;
rank 0 alone writes the run dir (config, checkpoints, logs) and evaluates (``refpo_warp.runner.distributed``).
"""

from __future__ import annotations

import contextlib
import math
import time
from pathlib import Path
from typing import Any

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.config.resolve import Resolution
from refpo_warp.config.run_options import notice_text
from refpo_warp.config.saved import RUN_CONFIG, resolve_run
from refpo_warp.config.yaml_files import dump_config
from refpo_warp.evaluation.evaluate_policy import Evaluator, make_eval_envs, periodic_evaluator
from refpo_warp.evaluation.evaluate_run import evaluate_run
from refpo_warp.evaluation.videos import run_video, wants_video
from refpo_warp.render.gl import select_gl_platform
from refpo_warp.runner.build import build_runner, env_steps_per_iteration, num_iterations, seed_everything
from refpo_warp.runner.checkpoints import checkpoint_progress, latest_checkpoint, load_latest
from refpo_warp.runner.distributed import process_rank
from refpo_warp.runner.progress import progress_path, read_rows, truncate_after
from refpo_warp.runner.run_dir import RUN_FILES, check_new_run_dir, check_writable, run_lock
from refpo_warp.runner.run_state import RUN_STATE_KEY, restore_run_state
from refpo_warp.runner.runner import Runner
from refpo_warp.training.fine_tuning import actor_frozen, clone_statistics_kept
from refpo_warp.training.init_from import load_init_from
from refpo_warp.training.pieces import PieceEnd
from refpo_warp.utils.atomic_files import remove_stale_temp_files, write_json
from refpo_warp.utils.errors import STOPPED_FILE, ConfigError, NonFiniteLossError, tag_run_dir


def train(overrides: list[str] | dict[str, Any] | None = None) -> dict:
    """Train (or resume) a run and evaluate it; returns the evaluation results (``{}`` if ``eval.at_end`` is off).

    ``resume=true`` continues the newest usable checkpoint of ``run_dir``; it is an error when the run dir has no
    checkpoint (nothing is started from scratch behind the user's back). Without it, a run dir that already holds
    checkpoints is refused.
    """
    started = time.monotonic()  # stop_after_minutes counts from here
    flat = parse_overrides(overrides) if isinstance(overrides, list) else dict(overrides or {})
    run = resolve_run(flat)
    cfg = run.cfg
    run_dir, resume = Path(cfg["run_dir"]), cfg["resume"]
    check_writable(run_dir)
    checkpoint = latest_checkpoint(run_dir) if run_dir.is_dir() else None
    if checkpoint is not None and not resume:
        raise ConfigError(
            f"{run_dir} already holds checkpoints ({checkpoint.name}); pass resume=true to continue "
            f"that run, or choose another run_dir"
        )
    if checkpoint is None and resume:
        raise ConfigError(
            f"resume=true, but {run_dir} holds no checkpoint (model_<iteration>.pt) to continue from; "
            f"start it again without resume=true (that replaces its config.yaml and progress.jsonl)"
        )
    if not resume:
        check_new_run_dir(run_dir)
    rank = process_rank()
    with contextlib.ExitStack() as stack:
        locked = rank.is_main and run_dir.is_dir()
        if locked:
            stack.enter_context(run_lock(run_dir))
        if wants_video(cfg) and rank.is_main:
            select_gl_platform()  # before the envs import MuJoCo
        seed_everything(cfg["seed"] + rank.rank)
        env, runner = build_runner(run, run_dir)
        start, saved_state = 0, None
        if resume:  # every rank loads the checkpoint
            start, saved_state = _resume(runner, cfg, run_dir, flat, rank.world_size)
        elif cfg["init_from"]:  # a cloned actor that does not fit is refused here, before anything is written
            clone, warmup = load_init_from(runner, cfg, run.task), cfg["critic_warmup_iterations"]
            critic = f"; iterations 0..{warmup - 1} train the critic alone (critic_warmup_iterations)" if warmup else ""
            kept = "; the observation normalisers keep the data's statistics (clone_normalizer=keep)"
            kept = kept if cfg["clone_normalizer"] == "keep" else ""
            print(f"[refpo_warp] starting from the cloned actor {clone}{critic}{kept}", flush=True)
        # --- everything below writes (rank 0 only); everything above could refuse the run without touching the disk
        if rank.is_main:
            run_dir.mkdir(parents=True, exist_ok=True)
            if not locked:  # the directory did not exist before
                stack.enter_context(run_lock(run_dir))
            if not resume and latest_checkpoint(run_dir) is not None:  # another process got here first
                raise ConfigError(f"{run_dir} received checkpoints from another process meanwhile; not touching it")
            remove_stale_temp_files(run_dir, RUN_FILES)
            (run_dir / STOPPED_FILE).unlink(missing_ok=True)  # a resumed run goes on; a new one starts over
            if not resume:
                for stale in (progress_path(run_dir), run_dir / "eval.json", run_dir / "eval.prev.json"):
                    stale.unlink(missing_ok=True)
            else:
                truncate_after(run_dir, start - 1)
            dump_config(cfg, run_dir / RUN_CONFIG)
        with tag_run_dir(run_dir):
            piece = PieceEnd(cfg["stop_after_iterations"], cfg["stop_after_minutes"], start, started)
            return _train_and_evaluate(run, env, runner, run_dir, start, piece, saved_state)


def _resume(runner: Runner, cfg: dict, run_dir: Path, flat: dict, world_size: int = 1) -> tuple[int, Any]:
    """Load the newest usable checkpoint, apply a learning-rate override, restore the counters; returns the next
    iteration and the checkpoint's run state (generators and env, restored when learning starts)."""
    path, data = load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    iteration = int(data["iter"])
    env_steps, time_s = checkpoint_progress(data)
    if env_steps is None:  # not written by refpo_warp: read the count from the progress log, or assume this batch
        rows = [r for r in read_rows(run_dir) if r["iteration"] == iteration] if progress_path(run_dir).exists() else []
        env_steps = rows[-1]["env_steps"] if rows else (iteration + 1) * env_steps_per_iteration(cfg, world_size)
        time_s = rows[-1].get("time_s", 0.0) if rows else 0.0
    alg = runner.alg
    if "algorithm.learning_rate" in flat:  # rsl_rl restored the checkpoint's rate with the optimizer state
        restored = alg.optimizer.param_groups[0]["lr"]
        alg.learning_rate = float(cfg["algorithm"]["learning_rate"])
        for group in alg.optimizer.param_groups:
            group["lr"] = alg.learning_rate
        print(
            f"[refpo_warp] learning_rate {alg.learning_rate:g} from the command line replaces {restored:g} "
            f"restored from {path.name}",
            flush=True,
        )
    print(
        f"[refpo_warp] resuming {run_dir} from {path.name}: iteration {iteration}, {env_steps:,} env steps", flush=True
    )
    return runner.continue_after(iteration, env_steps, time_s or 0.0), data.get(RUN_STATE_KEY)


def _train_and_evaluate(
    run: Resolution, env: Any, runner: Runner, run_dir: Path, start: int, piece: PieceEnd, saved_state: Any
) -> dict:
    cfg = run.cfg
    rank = process_rank()
    total = num_iterations(cfg, rank.world_size)
    ranks = f" x {rank.world_size} ranks" if rank.is_distributed else ""
    steps = total * env_steps_per_iteration(cfg, rank.world_size)
    notice = notice_text(cfg["notice"], cfg, steps) if cfg["notice"] else None
    if notice:
        print(f"[refpo_warp] NOTE: {notice}", flush=True)
    print(
        f"[refpo_warp] {cfg['task']} / {cfg['algo']} on {env.device}: {env.num_envs} envs{ranks}, "
        f"iterations {start}..{total - 1} ({steps:,} env steps), run dir {run_dir}",
        flush=True,
    )
    interval = cfg["eval"]["interval"] = evaluation_interval(cfg, total)
    evaluate = None
    if interval > 0 and rank.is_main:  # rank 0 evaluates; its envs' streams go on from one evaluation to the next
        runner.eval_envs = make_eval_envs(run, interval=True)  # so checkpoints hold their state too
        evaluate = periodic_evaluator(run, runner, runner.eval_envs)
    if evaluate is not None and cfg["video"].get("interval"):
        evaluate = with_videos(evaluate, run, runner, run_dir, interval)
    stopped = None
    if total > start:
        # a new run starts its envs at random points of their time-out; a resumed one goes on from the saved envs
        restored = start > 0 and _restore(runner, saved_state)
        random_start = cfg["runner"]["init_at_random_ep_len"] and not restored
        try:
            warmup = int(cfg["critic_warmup_iterations"]) if cfg["init_from"] else 0
            kept = cfg["init_from"] and cfg["clone_normalizer"] == "keep"
            with clone_statistics_kept(runner.alg) if kept else contextlib.nullcontext():
                stopped = _learn_in_chunks(runner, start, total, interval, evaluate, random_start, warmup, piece)
        except NonFiniteLossError as err:  # the CLI's message says what survives and how to go on
            err.checkpoint, err.run_dir = latest_checkpoint(run_dir), run_dir
            err.learning_rate = float(runner.alg.learning_rate)
            if rank.is_main:
                _record_stop(run_dir, err)
            raise
    else:
        print(
            f"[refpo_warp] nothing to train: the run is at iteration {start} and the budget is {total} iterations "
            f"(raise max_iterations or total_env_steps to continue)",
            flush=True,
        )
    if stopped is not None:
        it, why = stopped
        runner.stop_here()
        if rank.is_main:
            print(
                f"[refpo_warp] stopped after iteration {it - 1} of 0..{total - 1} ({why}): model_{it - 1}.pt holds "
                f"the run's state; refpo train run_dir={run_dir} resume=true continues it",
                flush=True,
            )
        return {}
    results = {}
    if cfg["eval"]["at_end"] and rank.is_main:
        results = evaluate_run(run_dir, run, runner=runner)
        log_final_evaluation(runner, results)
    if cfg["video"].get("at_end") and rank.is_main:
        results["videos"] = [str(p) for p in run_video(run, runner, run_dir, "final")]
    if rank.is_main:
        print(training_summary(cfg, runner, run_dir, results), flush=True)
    if notice:
        print(f"[refpo_warp] NOTE: {notice}", flush=True)
    return results


def evaluation_interval(cfg: dict, total: int) -> int:
    """Iterations between periodic evaluations of a run of ``total`` iterations: ``eval.interval``, or 10 per run when
    it is null (0: off)."""
    if cfg["eval"]["interval"] is None:
        return max(1, math.ceil(total / 10))
    return int(cfg["eval"]["interval"])


def training_summary(cfg: dict, runner, run_dir: Path, results: dict) -> str:
    """The closing block: where every output went, the training budget spent and the final evaluation's numbers."""
    from refpo_warp.utils.console import headline_numbers, run_outputs, summary_block

    logger, checkpoint = runner.logger, latest_checkpoint(run_dir)
    last = checkpoint.stem.split("_")[-1] if checkpoint is not None else "-"
    spent = [("trained", f"iterations 0..{last}, {int(logger.tot_timesteps):,} env steps, {logger.tot_time:.0f} s")]
    title = f"Trained {cfg['task']} / {cfg['algo']} (seed {cfg['seed']})"
    return summary_block(title, run_outputs(run_dir, checkpoint, results), spent + headline_numbers(results))


def with_videos(evaluate: Evaluator, run: Resolution, runner: Runner, run_dir: Path, interval: int) -> Evaluator:
    """The periodic evaluator, also recording a video (``videos/it<iteration>``) at every ``video.interval``-th
    evaluation; the recording leaves the training's random streams as they were."""
    every = int(run.cfg["video"]["interval"])

    def evaluate_and_record(it: int, is_last: bool) -> dict[str, float]:
        out = evaluate(it, is_last)
        if out and ((it + 1) // interval) % every == 0 and not is_last:
            run_video(run, runner, run_dir, f"it{it}")
        return out

    return evaluate_and_record


def _restore(runner: Runner, saved_state: Any) -> bool:
    """Put the checkpoint's generators and env state back (just before learning: nothing after may draw from them);
    returns whether the env's state was restored."""
    if process_rank().is_distributed:  # the checkpoint holds rank 0's envs only
        print("[refpo_warp] note: a run of several ranks resumes from fresh envs (not bit-identical)", flush=True)
        return False
    why = restore_run_state(runner.env, runner.logger, runner.eval_envs, saved_state)
    if why is not None:
        print(f"[refpo_warp] note: resuming from fresh envs, not bit-identical to an unbroken run: {why}", flush=True)
    return why is None


def _record_stop(run_dir: Path, err: NonFiniteLossError) -> None:
    """``stopped.json``: why and where the run stopped, so a sweep keeps it as its outcome instead of continuing it."""
    rows = read_rows(run_dir) if progress_path(run_dir).exists() else []
    last = rows[-1] if rows else {}
    write_json(
        {
            "reason": "non-finite loss",
            "error": str(err),
            "last_logged_iteration": last.get("iteration"),
            "env_steps": last.get("env_steps"),
            "newest_checkpoint": err.checkpoint.name if err.checkpoint else None,
        },
        run_dir / STOPPED_FILE,
    )


def _learn_in_chunks(
    runner,
    start: int,
    total: int,
    interval: int,
    evaluate,
    init_at_random_ep_len: bool,
    warmup: int = 0,
    piece: PieceEnd | None = None,
) -> tuple[int, str] | None:
    """Iterations ``start .. total - 1`` in chunks that end where periodic evaluation is due (every ``interval``
    iterations and at the last); the evaluation runs here, between chunks, and its numbers join the progress row
    of the chunk's last iteration (``eval/return_N<n>`` ...). Every rank learns in the same chunks. Iterations
    below ``warmup`` (a fine-tuning run's critic warm-up) keep the actor frozen, in chunks of their own. ``piece``
    may end the call early (``refpo_warp.training.pieces``): returns (the next iteration, why) then, else None."""
    it = start
    while it < total:
        end = min(total, (it // interval + 1) * interval) if interval > 0 else total
        if it < warmup:
            end = min(end, warmup)
        if piece is not None:
            end = piece.chunk_end(it, end)
        frozen = actor_frozen(runner.alg) if it < warmup else contextlib.nullcontext()
        with frozen:
            runner.learn_chunk(end - it, total, init_at_random_ep_len=init_at_random_ep_len and it == start)
        evaluated = evaluate(end - 1, end == total) if evaluate is not None else {}
        runner.end_chunk(evaluated)
        if evaluated and end < total:  # a checkpoint of this iteration was written before its evaluation
            runner.save_again(end - 1)
        it = end
        why = piece.reason(it) if piece is not None and it < total else None
        if why is not None:
            return it, why
    return None


def log_final_evaluation(runner, results: dict) -> None:
    """The final evaluation's returns, task metrics and scalar diagnostics as TensorBoard scalars (``Eval/...``)."""
    writer = runner.logger.writer
    if writer is None:
        return
    it = results["checkpoint_iteration"]
    for setting, summary in results["results"].items():
        for key, value in summary.items():
            if isinstance(value, float):
                writer.add_scalar(f"Eval/{setting}/{key}", value, it)
    for key, value in results.get("diagnostics", {}).items():
        if isinstance(value, float):
            writer.add_scalar(f"Eval/diagnostics/{key}", value, it)
    if hasattr(writer, "flush"):
        writer.flush()
