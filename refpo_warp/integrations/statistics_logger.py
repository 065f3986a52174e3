"""rsl_rl's ``Logger`` with an algorithm's statistics logged as statistics, for other frameworks' runners (mjlab's).

ReFPO's ``Flow/...`` keys become TensorBoard (W&B) tags of their own and lines of rsl_rl's per-iteration report,
not ``Loss/Flow/...`` and "Mean Flow/ratio_mean loss"; which key is which is
``refpo_warp.runner.logger.split_statistics``'s rule. ``StatisticsRunnerMixin`` puts the logger into any subclass of
rsl_rl's ``OnPolicyRunner``. Needs no framework but rsl_rl, and works on every rsl-rl-lib from 5.0.1 to 5.x:
rsl_rl's ``log`` gets the losses alone, and its report gets the statistics spliced in above its footer, in the
format rsl_rl prints its own prefixed episode values with.
"""

from __future__ import annotations

import contextlib
import io

from rsl_rl.utils.logger import Logger

from refpo_warp.runner.logger import split_statistics


def with_statistics(report: str, statistics: dict[str, float], width: int = 80, pad: int = 40) -> str:
    """rsl_rl's report with one ``<key>: <value>`` line per statistic above its footer (its last rule of dashes);
    at the end when it has none."""
    lines = "".join(f"{f'{key}:':>{pad}} {value:.4f}\n" for key, value in statistics.items())
    head, rule, tail = report.rpartition("-" * width + "\n")
    return f"{head}{lines}{rule}{tail}" if rule else report + lines


class StatisticsLogger(Logger):
    """``Logger`` whose ``log`` writes the statistics of ``loss_dict`` as tags and report lines of their own."""

    @classmethod
    def replacing(cls, logger: Logger, is_distributed: bool, gpu_global_rank: int) -> StatisticsLogger:
        """A StatisticsLogger with the settings of a runner's ``logger`` (built, not yet writing)."""
        new = cls(
            log_dir=logger.log_dir,
            cfg=logger.cfg,
            env_cfg=logger.env_cfg,
            num_envs=logger.num_envs,
            is_distributed=is_distributed,
            gpu_world_size=logger.gpu_world_size,
            gpu_global_rank=gpu_global_rank,
            device=logger.device,
        )
        new.git_status_repos = list(logger.git_status_repos)
        return new

    def log(
        self, it: int, start_it: int, total_it: int, collect_time: float, learn_time: float, loss_dict: dict, **kwargs
    ) -> None:
        losses, statistics = split_statistics(loss_dict)
        if self.writer is None or not statistics:
            super().log(it, start_it, total_it, collect_time, learn_time, losses, **kwargs)
            return
        report = io.StringIO()
        with contextlib.redirect_stdout(report):
            super().log(it, start_it, total_it, collect_time, learn_time, losses, **kwargs)
        for key, value in statistics.items():
            self.writer.add_scalar(key, value, it)
        width, pad = kwargs.get("width", 80), kwargs.get("pad", 40)
        print(with_statistics(report.getvalue(), statistics, width, pad), end="", flush=True)


class StatisticsRunnerMixin:
    """Put first in the bases of an ``OnPolicyRunner`` subclass: swaps its ``Logger`` for a ``StatisticsLogger``
    once the runner is built (before training starts its writer)."""

    # Set by OnPolicyRunner.__init__ (the class this mixes into).
    is_distributed: bool
    gpu_global_rank: int
    logger: Logger

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.logger = StatisticsLogger.replacing(self.logger, self.is_distributed, self.gpu_global_rank)
