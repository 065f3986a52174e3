"""The runner's logger: rsl_rl's ``Logger`` (TensorBoard, W&B, Neptune) plus one progress line per iteration,
``progress.jsonl`` holding every logged number, env steps that count every env step of an action chunk, and a stop
on a non-finite statistic.

Statistics named with a prefix (``Flow/ratio_max``) are TensorBoard tags of their own; the rest are rsl_rl's
``Loss/<key>``. Iterations count from 0 in the progress line, ``progress.jsonl`` and ``model_<it>.pt``.
"""

from __future__ import annotations

import contextlib
import io
import math
import statistics

import torch
from rsl_rl.utils.logger import Logger

from refpo_warp.runner.progress import append_row
from refpo_warp.utils.console import quiet_stdout
from refpo_warp.utils.errors import NonFiniteLossError


def split_statistics(loss_dict: dict) -> tuple[dict, dict[str, float]]:
    """``(losses, statistics)`` of an algorithm's ``update()`` dict: a key named with a prefix (``Flow/ratio_max``) is
    a statistic, a TensorBoard tag of its own; the rest are losses, rsl_rl's ``Loss/<key>``. The one home of this
    rule (the project's runner and the mjlab integration's both log by it)."""
    statistics_ = {key: float(value) for key, value in loss_dict.items() if "/" in key}
    losses = {key: value for key, value in loss_dict.items() if "/" not in key}
    return losses, statistics_


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

    def __init__(
        self, *args, log_full: bool = False, verbose: bool = False, env_steps_per_step: int = 1, **kwargs
    ) -> None:
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

    def log(
        self, it: int, start_it: int, total_it: int, collect_time: float, learn_time: float, loss_dict: dict, **kwargs
    ) -> None:
        bad = {k: v for k, v in loss_dict.items() if not math.isfinite(float(v))}
        if bad:
            raise NonFiniteLossError(f"Non-finite training statistics at iteration {it}: {bad}")
        if self.writer is None:
            return
        episode = _episode_means(self.ep_extras)
        losses, tagged = split_statistics(loss_dict)  # Flow/... are TensorBoard tags of their own
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
            assert total is not None  # log() sets _learn_total before it writes or holds a row
            print(self._progress_line(row["iteration"], total, row), flush=True)

    @staticmethod
    def _progress_line(it: int, total_it: int, row: dict) -> str:
        # 0-based, as model_<it>.pt and progress.jsonl count: the last iteration is total_it - 1
        width = len(str(total_it - 1))
        parts = [
            f"[it {it:>{width}}/{total_it - 1}]",
            f"steps {row['env_steps']:>11,}",
            f"{row['steps_per_s']:>8,} sps",
        ]
        if "reward_mean" in row:
            parts.append(f"return {row['reward_mean']:9.2f}")
            parts.append(f"len {row['episode_length_mean']:6.1f}")
        for key in (
            "Episode/success",
            "Flow/ratio_max",
            "Flow/clip_fraction",
            "Flow/explosion_rate",
            "Flow/straightness_error",
        ):
            if key in row:
                parts.append(f"{key.split('/')[-1]} {row[key]:.3g}")
        parts += [f"{k.split('/')[-1]} {v:.1f}" for k, v in row.items() if k.startswith("eval/return")]
        return "  ".join(parts)
