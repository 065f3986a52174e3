"""rsl_rl's OnPolicyRunner, extended (not forked) for long unattended runs.

- checkpoints are written atomically (temp file + rename), so a crash never leaves a truncated ``model_*.pt``,
  and carry the task, algorithm, env-step count and training time (``refpo_warp.checkpoints.META_KEY``);
- checkpoints are read only through ``refpo_warp.runner.checkpoints`` (``weights_only``: a file cannot run code);
  rsl_rl's ``load`` is replaced;
- one progress line per iteration (rsl_rl's full report with ``log_full``), plus ``progress.jsonl`` holding
  every logged number, which the plotting tools read; a resumed run continues its iterations and env steps;
  iterations count from 0 everywhere (progress line, ``progress.jsonl``, ``model_<it>.pt``);
- rsl_rl's construction and logging-writer messages (model structure, observation sets, git state) only with
  ``verbose``;
- a NaN/inf loss stops training before the next checkpoint, so the last checkpoint on disk stays good;
- ``learn_chunk``: a run learns in chunks (rsl_rl's ``learn`` each), so that the caller can evaluate between them
  (``refpo_warp.training``); one TensorBoard writer and checkpoints only at ``save_interval`` and at the run's end,
  as for a single ``learn``; ``end_chunk`` adds the caller's numbers to the chunk's last progress row;
- env steps count every env step: a policy step of an action-chunk env (``env_steps_per_step``) is several;
- multi-process training under torchrun on CUDA (NCCL) and on a CPU (gloo); rsl_rl itself only starts NCCL.
"""

from __future__ import annotations

import contextlib
import io
import math
import statistics

import torch
from rsl_rl.runners import OnPolicyRunner
from rsl_rl.utils.logger import Logger

from refpo_warp.runner.checkpoints import META_KEY, apply_checkpoint, check_fits, latest_checkpoint, read_checkpoint
from refpo_warp.runner.distributed import init_process_group, process_rank
from refpo_warp.runner.progress import append_row
from refpo_warp.utils.atomic_files import atomic_write
from refpo_warp.utils.console import quiet_stdout
from refpo_warp.utils.errors import NonFiniteLossError

__all__ = ["ProgressLogger", "Runner", "latest_checkpoint"]


def _episode_means(ep_extras: list[dict]) -> dict[str, float]:
    """Per-key means of the env's logged episode values over one iteration (what rsl_rl logs under Episode/)."""
    values: dict[str, list[torch.Tensor]] = {}
    for info in ep_extras:
        for key, value in info.items():
            values.setdefault(key, []).append(torch.as_tensor(value, dtype=torch.float32).reshape(-1).cpu())
    return {k if "/" in k else f"Episode/{k}": float(torch.cat(v).mean()) for k, v in values.items() if v}


class ProgressLogger(Logger):
    """rsl_rl's Logger (TensorBoard) plus a one-line console report, ``progress.jsonl`` and a non-finite check.

    ``env_steps_per_step``: env steps per policy step (an action-chunk env's chunk), so that ``env_steps`` and
    ``steps_per_s`` count env steps. While ``hold_last_row`` is set, the row of the last iteration of a ``learn`` call
    waits for ``end_chunk`` (which adds the evaluation run between chunks) before it is written and printed.
    """

    def __init__(self, *args, log_full: bool = False, verbose: bool = False, env_steps_per_step: int = 1,
                 **kwargs) -> None:  # fmt: skip
        super().__init__(*args, **kwargs)
        self.log_full = log_full
        self.verbose = verbose
        self.env_steps_per_step = int(env_steps_per_step)
        self.run_iterations: int | None = None  # the whole run's iteration count, for the progress line
        self.hold_last_row = False
        self.final_chunk = True
        self._held: dict | None = None
        self._writer_started = False
        self._learn_total: int | None = None

    def init_logging_writer(self) -> None:
        if self._writer_started:  # once per run, not once per learn() chunk
            return
        # rsl_rl reports the git state of each repository here; W&B / Neptune print links the user wants to see.
        service = str(self.cfg.get("logger", "tensorboard")).lower() in ("wandb", "neptune")
        with quiet_stdout(not (self.verbose or service)):
            super().init_logging_writer()
        self._writer_started = True

    def stop_logging_writer(self) -> None:
        if self.final_chunk:
            super().stop_logging_writer()

    def log(self, it: int, start_it: int, total_it: int, collect_time: float, learn_time: float,
            loss_dict: dict, **kwargs) -> None:  # fmt: skip
        bad = {k: v for k, v in loss_dict.items() if not math.isfinite(float(v))}
        if bad:
            raise NonFiniteLossError(f"Non-finite training statistics at iteration {it}: {bad}")
        if self.writer is None:
            return
        episode = _episode_means(self.ep_extras)
        # Statistics named with a prefix (Flow/...) are TensorBoard tags of their own; the rest are rsl_rl's Loss/.
        tagged = {k: float(v) for k, v in loss_dict.items() if "/" in k}
        losses = {k: v for k, v in loss_dict.items() if "/" not in k}
        sink = contextlib.nullcontext() if self.log_full else contextlib.redirect_stdout(io.StringIO())
        with sink:
            super().log(it, start_it, total_it, collect_time, learn_time, losses, **kwargs)
        for key, value in tagged.items():
            self.writer.add_scalar(key, value, it)
        # rsl_rl counted policy steps; the other steps of each action chunk (all ranks):
        policy_steps = self.cfg["num_steps_per_env"] * self.num_envs * self.gpu_world_size
        self.tot_timesteps += policy_steps * (self.env_steps_per_step - 1)
        row = {
            "iteration": it,
            "env_steps": self.tot_timesteps,
            "time_s": round(self.tot_time, 3),
            "steps_per_s": int(policy_steps * self.env_steps_per_step / max(collect_time + learn_time, 1e-9)),
        }
        if self.rewbuffer:
            row["reward_mean"] = statistics.mean(self.rewbuffer)
            row["episode_length_mean"] = statistics.mean(self.lenbuffer)
        row.update(episode)
        row.update({f"Loss/{k}": float(v) for k, v in losses.items()})
        row.update(tagged)
        self._learn_total = total_it
        if self.hold_last_row and it == total_it - 1:
            self._held = row
        else:
            self._write_row(row)

    def end_chunk(self, extra: dict[str, float]) -> None:
        """Add ``extra`` (e.g. ``eval/return_N10``) to the held row of the chunk's last iteration (and to TensorBoard
        at that iteration), then write and print the row."""
        row, self._held = self._held, None
        if row is None:  # not the main rank (or nothing held)
            return
        for key, value in extra.items():
            self.writer.add_scalar(key, value, row["iteration"])
        row.update(extra)
        self._write_row(row)

    def _write_row(self, row: dict) -> None:
        append_row(self.log_dir, row)
        if not self.log_full:
            total = self.run_iterations or self._learn_total
            print(self._progress_line(row["iteration"], total, row), flush=True)

    @staticmethod
    def _progress_line(it: int, total_it: int, row: dict) -> str:
        # 0-based, as model_<it>.pt and progress.jsonl count: the last iteration is total_it - 1
        width = len(str(total_it - 1))
        parts = [f"[it {it:>{width}}/{total_it - 1}]", f"steps {row['env_steps']:>11,}",
                 f"{row['steps_per_s']:>8,} sps"]
        if "reward_mean" in row:
            parts.append(f"return {row['reward_mean']:9.2f}")
            parts.append(f"len {row['episode_length_mean']:6.1f}")
        for key in ("Episode/success", "Flow/ratio_max", "Flow/clip_fraction", "Flow/explosion_rate",
                    "Flow/straightness_error"):  # fmt: skip
            if key in row:
                parts.append(f"{key.split('/')[-1]} {row[key]:.3g}")
        parts += [f"{k.split('/')[-1]} {v:.1f}" for k, v in row.items() if k.startswith("eval/return")]
        return "  ".join(parts)


class Runner(OnPolicyRunner):
    """OnPolicyRunner with atomic, safely loaded checkpoints, a progress line per iteration, learning in chunks and
    a torch.distributed backend that matches the device; rsl_rl's own messages only with ``verbose``.

    ``run_info`` (``{"task", "algo"}``) is written into every checkpoint and checked when one is loaded.
    """

    def __init__(self, env, train_cfg: dict, log_dir: str | None = None, device: str = "cpu",
                 log_full: bool = False, run_info: dict | None = None,
                 verbose: bool = False) -> None:  # fmt: skip
        with quiet_stdout(not verbose):  # rsl_rl prints the observation sets and the models
            super().__init__(env, train_cfg, log_dir=log_dir, device=device)
        old = self.logger
        self.logger = ProgressLogger(
            log_dir=log_dir, cfg=self.cfg, env_cfg=env.cfg, num_envs=env.num_envs,
            is_distributed=self.is_distributed, gpu_world_size=self.gpu_world_size,
            gpu_global_rank=self.gpu_global_rank, device=device, log_full=log_full, verbose=verbose,
            env_steps_per_step=getattr(env, "env_steps_per_step", 1),
        )  # fmt: skip
        self.logger.git_status_repos = old.git_status_repos + [__file__]
        self.run_info = dict(run_info or {})
        self._learned = False
        self._final_chunk = True

    def learn_chunk(self, num_iterations: int, run_iterations: int, init_at_random_ep_len: bool = False) -> None:
        """The next ``num_iterations`` of a run of ``run_iterations`` (rsl_rl's ``learn``, resumed where the last
        chunk ended); then the caller may evaluate and must call ``end_chunk``. Checkpoints are written at
        ``save_interval`` and after the run's last iteration, not at the end of every chunk."""
        if self._learned:  # rsl_rl leaves current_learning_iteration at the last iteration it ran
            self.current_learning_iteration += 1
        self._final_chunk = self.current_learning_iteration + num_iterations >= run_iterations
        self.logger.run_iterations = run_iterations
        self.logger.final_chunk = self._final_chunk
        self.logger.hold_last_row = True
        # rsl_rl's learn() broadcasts rank 0's parameters first. The ranks are identical after the first chunk (the
        # gradients are all-reduced), and a later broadcast would load into the normaliser buffers that rsl-rl-lib
        # < 5.5 re-creates during the inference-mode rollout, which torch refuses: broadcast once per run.
        synchronised = self._learned and self.is_distributed
        if synchronised:
            self.alg.broadcast_parameters = _already_synchronised
        try:
            self.learn(num_iterations, init_at_random_ep_len=init_at_random_ep_len)
        finally:
            if synchronised:
                del self.alg.broadcast_parameters  # the class's method again
            self._learned = True
            self._final_chunk = self.logger.final_chunk = True

    def end_chunk(self, extra: dict[str, float]) -> None:
        """Finish the chunk's last progress row with ``extra`` (the numbers the caller measured after it)."""
        self.logger.end_chunk(extra)

    def _configure_multi_gpu(self) -> None:
        """rsl_rl's multi-GPU set-up, with the backend picked by the device: NCCL on CUDA, gloo on a CPU.

        Sets the same attributes as rsl_rl's version (ranks, world size, ``cfg["multi_gpu"]``), which always starts
        NCCL and so cannot run (or be tested) on a CPU. A process group that already exists is reused.
        """
        rank = process_rank()
        self.gpu_world_size, self.is_distributed = rank.world_size, rank.is_distributed
        self.gpu_local_rank, self.gpu_global_rank = rank.local_rank, rank.rank
        if not rank.is_distributed:
            self.cfg["multi_gpu"] = None
            return
        self.cfg["multi_gpu"] = {"global_rank": rank.rank, "local_rank": rank.local_rank, "world_size": rank.world_size}
        device = torch.device(self.device)
        if device.type == "cuda" and device != torch.device("cuda", rank.local_rank):
            raise ValueError(f"Device '{self.device}' does not match the device of local rank {rank.local_rank}: "
                             f"cuda:{rank.local_rank}")  # fmt: skip
        init_process_group(rank, self.device)

    def save(self, path: str, infos: dict | None = None) -> None:
        """Write the checkpoint atomically: a reader never sees a partial file, a crash keeps the previous one."""
        if not self._final_chunk and self.current_learning_iteration % self.cfg["save_interval"]:
            return  # the end of a chunk that is not the run's end (save_interval saves fall on multiples)
        saved = self.alg.save()
        saved["iter"] = self.current_learning_iteration
        saved["infos"] = infos
        saved[META_KEY] = {**self.run_info, "env_steps": int(self.logger.tot_timesteps),
                           "time_s": float(self.logger.tot_time)}  # fmt: skip
        with atomic_write(path) as f:
            torch.save(saved, f)
        self.logger.save_model(path, self.current_learning_iteration)

    def load(self, path: str, load_cfg: dict | None = None, strict: bool = True, map_location: str | None = None):
        """rsl_rl's ``load`` without unpickling arbitrary objects, refusing files of another task or shape."""
        data = read_checkpoint(path, map_location=map_location or self.device)
        check_fits(path, data, self.alg, self.run_info.get("task"), self.run_info.get("algo"))
        apply_checkpoint(self, path, data, load_cfg, strict)
        return data.get("infos")

    def continue_after(self, iteration: int, env_steps: int, time_s: float) -> int:
        """Set the counters of a run resumed from the checkpoint of ``iteration``; returns the next iteration."""
        self.current_learning_iteration = iteration + 1
        self.logger.tot_timesteps = int(env_steps)
        self.logger.tot_time = float(time_s)
        return self.current_learning_iteration


def _already_synchronised() -> None:
    """Stands in for ``broadcast_parameters`` after a run's first chunk (see ``Runner.learn_chunk``)."""
