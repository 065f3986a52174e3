"""Figures of a sweep report: the paper's Figure 3 (per-task reward curves, 10-step/1-step gap shaded, mean over
seeds), Figure 4 (training return vs proxy-ratio spikes per update) and Figure 5b (action latency, N = 1 vs N = 10).

Curves come from each run's ``progress.jsonl`` (``eval/return_N10``, ``eval/return_N1``, ``eval/return``,
``reward_mean``, ``Flow/ratio_max``); latency from the JSON of ``refpo bench latency out=PATH``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from refpo_warp.evaluation.curves import plt, readable_log_axis, seed_stats, series, training_curves
from refpo_warp.runner.progress import read_rows
from refpo_warp.utils.atomic_files import save_figure

RATIO_KEYS = ("Flow/ratio_max", "loss/ratio_max")  # the shared name, then the name of runs logged before it
CURVE_KEYS = ("eval/return_N10", "eval/return_N1", "eval/return", "reward_mean")
EXPLOSION_RATIO = math.exp(3.0)  # |log rho| > 3: the paper's explosion threshold on the proxy ratio


def ratio_key(rows: list[dict]) -> str | None:
    return next((k for k in RATIO_KEYS if any(k in r for r in rows)), None)


def seed_mean(curves: list[tuple[list[float], list[float]]]) -> tuple[list[float], list[float]]:
    """Mean over seeds at the env-step counts every seed has (``refpo_warp.evaluation.curves.seed_stats``)."""
    steps, mean, _, _ = seed_stats(curves)
    return steps, mean


def _grid(n: int, cols: int, width: float, height: float):
    cols = max(1, min(cols, n))
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.axis("off")
    return fig, list(axes.flat[:n])


def reward_curve_grid(curves: dict[str, dict[str, dict[str, tuple[list, list]]]], path: Path) -> Path:
    """Figure 3: one panel per task; per method the seed-mean 10-step (solid) and 1-step (dashed) evaluation
    returns with the gap shaded; a Gaussian method's evaluation return, or the training return when a run has
    no periodic evaluation (dotted)."""
    fig, axes = _grid(len(curves), 5, 3.4, 2.7)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    handles: dict[str, object] = {}
    for ax, (task, methods) in zip(axes, curves.items()):
        for (name, keys), color in zip(methods.items(), colors * 4):
            hi, lo = keys.get("eval/return_N10", ([], [])), keys.get("eval/return_N1", ([], []))
            if hi[0]:
                handles[f"{name} (10-step)"] = ax.plot(*hi, color=color, lw=1.6)[0]
                if lo[0]:
                    handles[f"{name} (1-step)"] = ax.plot(*lo, color=color, lw=1.0, ls="--")[0]
                    if lo[0] == hi[0]:
                        ax.fill_between(hi[0], lo[1], hi[1], color=color, alpha=0.2, lw=0)
            elif keys.get("eval/return", ([], []))[0]:
                handles[name] = ax.plot(*keys["eval/return"], color=color, lw=1.6)[0]
            elif keys.get("reward_mean", ([], []))[0]:
                handles[f"{name} (training return)"] = ax.plot(*keys["reward_mean"], color=color, lw=1.0, ls=":")[0]
        ax.set_title(task.removeprefix("dmc_"), fontsize=9)
        ax.tick_params(labelsize=7)
        ax.xaxis.get_offset_text().set_fontsize(7)
        ax.grid(alpha=0.3)
    for ax in axes[-min(5, len(axes)) :]:
        ax.set_xlabel("env steps", fontsize=8)
    axes[0].set_ylabel("episode return (mean over seeds)", fontsize=8)
    fig.legend(
        list(handles.values()),
        list(handles),
        loc="lower center",
        ncol=min(4, max(1, len(handles))),
        fontsize=7,
        frameon=False,
    )
    fig.tight_layout(rect=(0, 0.06 + 0.02 * math.ceil(len(handles) / 4), 1, 1))
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


def ratio_spikes(panels: dict[str, dict[str, list[dict]]], path: Path, seed: int) -> Path:
    """Figure 4: per task (columns) the training return per update with the periodic 10-step evaluations as dots
    (top) and the largest proxy ratio of each update on a log axis (bottom), one colour per method, for one seed;
    the dashed line is exp(3)."""
    fig, axes = plt.subplots(2, len(panels), figsize=(3.8 * len(panels), 5.0), squeeze=False, sharex="col")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for col, (task, methods) in enumerate(panels.items()):
        top, bottom = axes[0, col], axes[1, col]
        for (name, rows), color in zip(methods.items(), colors * 4):
            top.plot(*series(rows, "reward_mean"), color=color, lw=1.0, label=f"{name} (training)")
            top.plot(
                *series(rows, "eval/return_N10"),
                color=color,
                ls="none",
                marker="o",
                ms=3,
                label=f"{name} (evaluation, N=10)",
            )
            key = ratio_key(rows)
            if key:
                bottom.plot(*series(rows, key), color=color, lw=0.9, label=name)
        bottom.axhline(EXPLOSION_RATIO, color="0.4", ls="--", lw=0.8, label="exp(3)")
        readable_log_axis(bottom)
        top.set_title(f"{task.removeprefix('dmc_')} (seed {seed})", fontsize=9)
        bottom.set_xlabel("env steps", fontsize=8)
        for ax in (top, bottom):
            ax.grid(alpha=0.3, which="both" if ax is bottom else "major")
            ax.tick_params(labelsize=7)
    axes[0, 0].set_ylabel("episode return", fontsize=8)
    axes[1, 0].set_ylabel("max proxy ratio per update", fontsize=8)
    axes[0, 0].legend(fontsize=6)
    axes[1, 0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


def latency_bars(latency: dict, path: Path, names: dict[str, str] | None = None) -> Path:
    """Figure 5b: action latency per policy and flow-step count N, one panel per (task, batch size)."""
    names = names or {}
    groups: dict[tuple[str, int], list[dict]] = {}
    for row in latency["rows"]:
        groups.setdefault((row["task"], row["batch"]), []).append(row)
    fig, axes = plt.subplots(1, len(groups), figsize=(3.6 * len(groups), 3.8), squeeze=False)
    for ax, ((task, batch), rows) in zip(axes[0], groups.items()):
        labels = [
            names.get(r["algo"], r["algo"]) + (f", N={r['flow_steps']}" if r.get("flow_steps") else ", mean")
            for r in rows
        ]
        values = [r["latency_ms"] for r in rows]
        bars = ax.bar(range(len(rows)), values, color=["C0" if r.get("flow_steps") != 1 else "C2" for r in rows])
        ax.bar_label(bars, labels=[f"{v:.3g}" for v in values], fontsize=7)
        ax.set_xticks(range(len(rows)), labels, fontsize=7, rotation=30, ha="right")
        ax.set_title(f"{task.removeprefix('dmc_')}, {batch} obs per call", fontsize=9)
        ax.set_ylabel("latency per action batch (ms)", fontsize=8)
        ax.tick_params(axis="y", labelsize=7)
        ax.grid(axis="y", alpha=0.3)
    fig.suptitle(f"action latency on {latency.get('device_name', latency.get('device', '?'))}", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


def sweep_curves(sweep_dir: str | Path, out_dir: str | Path | None = None, window: int = 5) -> list[Path]:
    """Per task of a sweep dir (``<task>/<method>/seed<k>``, as refpo sweep writes it): ``<task>_curves.png``
    with one line per method (mean over seeds, band: their range). Prints each seed's training episode length and
    return at the start and the end (means over the first and the last ``window`` iterations)."""
    sweep_dir = Path(sweep_dir)
    out = Path(out_dir or sweep_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for task_dir in sorted(p for p in sweep_dir.iterdir() if p.is_dir()):
        runs = {}
        for method_dir in sorted(p for p in task_dir.iterdir() if p.is_dir()):
            seeds = sorted(p for p in method_dir.glob("seed*") if (p / "progress.jsonl").is_file())
            runs[method_dir.name] = [read_rows(p) for p in seeds]
            for seed_dir, rows in zip(seeds, runs[method_dir.name]):
                length = [r["episode_length_mean"] for r in rows if "episode_length_mean" in r]
                ret = [r["reward_mean"] for r in rows if "reward_mean" in r]
                if len(length) >= 2 * window and len(ret) >= 2 * window:
                    first, last = np.mean(length[:window]), np.mean(length[-window:])
                    print(
                        f"{task_dir.name} {method_dir.name} {seed_dir.name}: episode length {first:.1f} -> "
                        f"{last:.1f} ({last / first:.2f}x), return {np.mean(ret[:window]):.2f} -> "
                        f"{np.mean(ret[-window:]):.2f}, {rows[-1]['env_steps']:,} env steps, "
                        f"{rows[-1]['time_s']:.0f} s"
                    )
        if any(runs.values()):
            written.append(training_curves({k: v for k, v in runs.items() if v}, out / f"{task_dir.name}_curves.png"))
    return written
