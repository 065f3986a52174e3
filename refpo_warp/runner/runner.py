"""rsl_rl's OnPolicyRunner, extended (not forked) for long unattended runs.

- checkpoints are written atomically (temp file + rename), so a crash never leaves a truncated ``model_*.pt``,
  and carry the task, algorithm, env-step count and training time (``refpo_warp.runner.checkpoints.META_KEY``);
- checkpoints are read only through ``refpo_warp.runner.checkpoints`` (``weights_only``: a file cannot run code);
  rsl_rl's ``load`` is replaced;
- one progress line per iteration (rsl_rl's full report with ``log_full``), plus ``progress.jsonl`` holding
  every logged number, which the plotting tools read; a resumed run continues its iterations and env steps;
  iterations count from 0 everywhere (progress line, ``progress.jsonl``, ``model_<it>.pt``);
- rsl_rl's construction and logging-writer messages (model structure, observation sets, git state) only with
  ``verbose``;
- a NaN/inf loss stops training before the next checkpoint, so the last checkpoint on disk stays good;
- ``learn_chunk``: a run learns in chunks (rsl_rl's ``learn`` each), so that the caller can evaluate between them
  (``refpo_warp.training.train_run``); one TensorBoard writer and checkpoints only at ``save_interval`` and at the
  run's end, as for a single ``learn``; ``end_chunk`` adds the caller's numbers to the chunk's last progress row;
- env steps count every env step: a policy step of an action-chunk env (``env_steps_per_step``) is several;
- multi-process training under torchrun on CUDA (NCCL) and on a CPU (gloo); rsl_rl itself only starts NCCL.
"""

from __future__ import annotations

import os

import torch
from rsl_rl.runners import OnPolicyRunner

from refpo_warp.runner.checkpoints import META_KEY, apply_checkpoint, check_fits, read_checkpoint
from refpo_warp.runner.distributed import init_process_group, process_rank
from refpo_warp.runner.logger import ProgressLogger
from refpo_warp.runner.run_state import RUN_STATE_KEY, capture_run_state
from refpo_warp.utils.atomic_files import atomic_write
from refpo_warp.utils.console import quiet_stdout

__all__ = ["Runner"]


class Runner(OnPolicyRunner):
    """OnPolicyRunner with atomic, safely loaded checkpoints, a progress line per iteration, learning in chunks and
    a torch.distributed backend that matches the device; rsl_rl's own messages only with ``verbose``.

    ``run_info`` (``{"task", "algo"}``) is written into every checkpoint and checked when one is loaded.
    """

    def __init__(
        self,
        env,
        train_cfg: dict,
        log_dir: str | None = None,
        device: str = "cpu",
        log_full: bool = False,
        run_info: dict | None = None,
        verbose: bool = False,
    ) -> None:
        with quiet_stdout(not verbose):  # rsl_rl prints the observation sets and the models
            super().__init__(env, train_cfg, log_dir=log_dir, device=device)
        old = self.logger
        self.logger: ProgressLogger = ProgressLogger(
            log_dir=log_dir,
            cfg=self.cfg,
            env_cfg=env.cfg,
            num_envs=env.num_envs,
            is_distributed=self.is_distributed,
            gpu_world_size=self.gpu_world_size,
            gpu_global_rank=self.gpu_global_rank,
            device=device,
            log_full=log_full,
            verbose=verbose,
            env_steps_per_step=getattr(env, "env_steps_per_step", 1),
        )
        self.logger.git_status_repos = old.git_status_repos + [__file__]
        self.run_info = dict(run_info or {})
        self._learned = False
        self._final_chunk = True
        self._last_saved: int | None = None
        self.eval_envs: dict = {}  # the periodic evaluation's envs, whose state checkpoints hold too

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
            raise ValueError(
                f"Device '{self.device}' does not match the device of local rank {rank.local_rank}: "
                f"cuda:{rank.local_rank}"
            )
        init_process_group(rank, self.device)

    def save(self, path: str, infos: dict | None = None) -> None:
        """Write the checkpoint atomically: a reader never sees a partial file, a crash keeps the previous one."""
        if not self._final_chunk and self.current_learning_iteration % self.cfg["save_interval"]:
            return  # the end of a chunk that is not the run's end (save_interval saves fall on multiples)
        saved = self.alg.save()
        saved["iter"] = self.current_learning_iteration
        saved["infos"] = infos
        saved[META_KEY] = {
            **self.run_info,
            "env_steps": int(self.logger.tot_timesteps),
            "time_s": float(self.logger.tot_time),
        }
        saved[RUN_STATE_KEY] = capture_run_state(
            self.env, self.logger, self.eval_envs
        )  # for a resume that goes on bit for bit
        with atomic_write(path) as f:
            torch.save(saved, f)
        self._last_saved = self.current_learning_iteration
        self.logger.save_model(path, self.current_learning_iteration)

    def save_again(self, iteration: int) -> None:
        """Write the checkpoint of ``iteration`` again if this run wrote it: after the periodic evaluation that
        followed it, whose envs' state a resume from it needs."""
        if self._last_saved == iteration == self.current_learning_iteration and self.logger.writer is not None:
            self.save(os.path.join(self.logger.log_dir, f"model_{iteration}.pt"))

    def stop_here(self) -> None:
        """End this call's piece of the run after the iteration just learned: write its checkpoint (outside
        ``save_interval`` too) and close the logging writer; ``resume=true`` continues from it."""
        self._final_chunk = self.logger.final_chunk = True
        if self.logger.writer is not None:
            self.save(os.path.join(self.logger.log_dir, f"model_{self.current_learning_iteration}.pt"))
            self.logger.stop_logging_writer()

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
