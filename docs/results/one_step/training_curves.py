"""The sweep's finished runs by task, method and seed, and <task>_one_step.png: per method the periodic N = 10 and N = 1
returns, the one-step error and ratio and the Reflow coefficient over env steps (mean over seeds, their range as a
band), with the last value of each."""

from pathlib import Path

import numpy as np

from refpo_warp.utils.errors import DataFileError

PANELS = [
    ("eval/return_N10", "N = 10 return", False),
    ("eval/return_N1", "N = 1 return", False),
    ("Flow/one_step_error", "one-step error", True),
    ("Flow/one_step_ratio", "one-step ratio", True),
    ("Flow/reflow_coef", "Reflow coefficient λ", False),
]


def method_runs(sweep: Path) -> dict[str, dict[str, dict[int, Path]]]:
    """{task: {method label: {seed: run dir}}} of the finished runs (those with an eval.json)."""
    out: dict[str, dict[str, dict[int, Path]]] = {}
    for eval_file in sorted(sweep.glob("*/*/seed*/eval.json")):
        run = eval_file.parent
        out.setdefault(run.parent.parent.name, {}).setdefault(run.parent.name, {})[int(run.name[4:])] = run
    if not out:
        raise DataFileError(f"{sweep}: no finished runs (<task>/<method>/seed<k>/eval.json); is it a sweep dir?")
    return out


def training_figures(runs, out: Path) -> dict:
    from refpo_warp.evaluation.curves import plt, readable_log_axis, seed_stats, series
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.utils.atomic_files import save_figure

    numbers: dict[str, dict] = {}
    for task, methods in runs.items():
        fig, axes = plt.subplots(1, len(PANELS), figsize=(3.3 * len(PANELS), 2.8))
        numbers[task] = {}
        for (label, seeds), color in zip(sorted(methods.items()), plt.rcParams["axes.prop_cycle"].by_key()["color"]):
            rows = [read_rows(run) for run in seeds.values()]
            numbers[task][label] = {}
            for ax, (key, title, log) in zip(axes, PANELS):
                steps, mean, low, high = seed_stats([series(r, key) for r in rows])
                if not steps:
                    continue
                ax.plot(np.array(steps) / 1e6, mean, color=color, lw=1.4, label=label)
                ax.fill_between(np.array(steps) / 1e6, low, high, color=color, alpha=0.15, lw=0)
                ax.set_title(title, fontsize=9)
                if log:
                    readable_log_axis(ax)
                numbers[task][label][key] = {"env_steps": steps[-1], "mean": mean[-1], "low": low[-1], "high": high[-1]}
        for ax in axes:
            ax.set_xlabel("env steps (M)", fontsize=8)
            ax.tick_params(labelsize=7)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"{task}: one-step sampler over training (mean over seeds, range shaded)", fontsize=10)
        fig.tight_layout()
        save_figure(fig, out / f"{task}_one_step.png")
        plt.close(fig)
    return numbers
