"""Training-curve figures from ``progress.jsonl``: returns (with the 10-step/1-step gap), episode lengths, success
and flow diagnostics.

Several runs can share one figure (e.g. FPO vs ReFPO): each run dir is one coloured line.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib import ticker

from refpo_warp.runner.progress import read_rows
from refpo_warp.utils.atomic_files import save_figure
from refpo_warp.utils.errors import DataFileError

DIAGNOSTICS = (
    ("Flow/ratio_max", "max ratio per update"),
    ("Flow/clip_fraction", "clip fraction"),
    ("Flow/explosion_rate", "Explosion Rate (per action)"),
    ("Flow/straightness_error", "Straightness Error"),
)


def series(rows: list[dict], key: str) -> tuple[list[float], list[float]]:
    """(env steps, values) of ``key`` over the progress rows that have it."""
    points = [(r["env_steps"], r[key]) for r in rows if key in r and "env_steps" in r]
    return [p[0] for p in points], [p[1] for p in points]


def seed_stats(curves: list[tuple[list[float], list[float]]]):
    """(steps, mean, low, high) over seeds' (env steps, values) curves, at the env-step counts every seed has; if
    they share none (runs of different lengths), at each count over the seeds that have it."""
    curves = [c for c in curves if c[0]]
    if not curves:
        return [], [], [], []
    tables = [dict(zip(x, y)) for x, y in curves]
    common = set(tables[0]).intersection(*tables[1:])
    steps = sorted(common) if common else sorted(set().union(*tables))
    values = [[t[s] for t in tables if s in t] for s in steps]
    return steps, [float(np.mean(v)) for v in values], [min(v) for v in values], [max(v) for v in values]


def _seed_series(seeds: list[list[dict]], key: str):
    """``seed_stats`` of ``key`` over the seeds' runs as arrays (None if no run has the key)."""
    steps, mean, low, high = seed_stats([series(rows, key) for rows in seeds])
    return (np.asarray(steps, float), np.asarray(mean), np.asarray(low), np.asarray(high)) if steps else None


def _label(run_dir: Path) -> str:
    return f"{run_dir.parent.name}/{run_dir.name}" if run_dir.parent.name else run_dir.name


def _as_seeds(rows_or_seeds: list) -> list[list[dict]]:
    return rows_or_seeds if rows_or_seeds and isinstance(rows_or_seeds[0], list) else [rows_or_seeds]


def _band(ax, stats, color, label, **line) -> None:
    x, mean, low, high = stats
    ax.plot(x, mean, color=color, label=label, **line)
    if not np.array_equal(low, high):
        ax.fill_between(x, low, high, color=color, alpha=0.12, lw=0)


def training_curves(runs: dict[str, list], path: Path) -> Path:
    """Return, episode length and (where the task has it) success over env steps, one colour per run.

    A run is its ``progress.jsonl`` rows, or a list of such lists (seeds): then the line is the seeds' mean and the
    band their range. Returns are the periodic evaluation's at N = 10 and N = 1 with the gap shaded (paper Figure 3),
    else the Gaussian policy's evaluation return, else the training return; episode length and success are the
    training episodes'.
    """
    seeds = {label: _as_seeds(rows) for label, rows in runs.items()}
    rows = [r for group in seeds.values() for run in group for r in run]
    success_key = next((k for k in ("Episode/success", "Episode/success_rate") if any(k in r for r in rows)), None)
    panels = ["return", "episode length"] + (["success"] if success_key else [])
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 3.6), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for (label, group), color in zip(seeds.items(), colors * 4):
        high, low = _seed_series(group, "eval/return_N10"), _seed_series(group, "eval/return_N1")
        if high and low and len(high[0]) == len(low[0]):
            _band(axes[0, 0], high, color, f"{label} 10-step", lw=1.8)
            _band(axes[0, 0], low, color, f"{label} 1-step", lw=1.0, ls="--")
            axes[0, 0].fill_between(high[0], low[1], high[1], color=color, alpha=0.2, lw=0)
        else:
            stats = _seed_series(group, "eval/return") or _seed_series(group, "reward_mean")
            if stats:
                _band(axes[0, 0], stats, color, label, lw=1.5)
        for ax, key in zip(axes[0, 1:], ["episode_length_mean", success_key]):
            stats = _seed_series(group, key) if key else None
            if stats:
                _band(ax, stats, color, label, lw=1.5)
    for ax, title in zip(axes[0], panels):
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("env steps")
        ax.grid(alpha=0.3)
    _legend(axes[0, 0])
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


class _ReadableLogLocator(ticker.LogLocator):
    """Ticks at 1, 2, 5 x 10^k over at most 2.5 decades, else at powers of ten alone (at most 7 of them)."""

    def tick_values(self, vmin, vmax):
        decades = abs(np.log10(vmax) - np.log10(vmin)) if vmin > 0 and vmax > 0 else 0.0
        self.set_params(subs=(1.0, 2.0, 5.0) if decades <= 2.5 else (1.0,), numticks=7)
        return super().tick_values(vmin, vmax)


def _legend(ax) -> None:
    """The axes' legend, where it has curves (a clone's log of epochs has no returns, a PPO run no ratio spikes)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)


def readable_log_axis(ax) -> None:
    """Log scale with a few ticks printed as plain numbers (not 10^k superscripts), chosen when the axis is drawn."""
    ax.set_yscale("log")
    ax.yaxis.set_major_locator(_ReadableLogLocator(base=10))
    ax.yaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(ticker.NullFormatter())


def diagnostic_curves(runs: dict[str, list[dict]], path: Path) -> Path:
    """Ratio spikes, clip fraction, Explosion Rate and Straightness Error per update (paper §4.2 diagnostics)."""
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    for (key, title), ax in zip(DIAGNOSTICS, axes.flat):
        for label, rows in runs.items():
            x, y = series(rows, key)
            if x:
                ax.plot(x, y, lw=1.0, label=label)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    readable_log_axis(axes[0, 0])
    for ax in axes[1]:
        ax.set_xlabel("env steps")
    _legend(axes[0, 0])
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


def figure_grid(run_dirs: list[Path], path: Path) -> Path | None:
    """Tile the evaluation figures of several runs (rows: runs, columns: figures listed in their eval.json)."""
    names = []
    for run_dir in run_dirs:
        report = Path(run_dir) / "eval.json"
        try:
            figures = json.loads(report.read_text()).get("figures", []) if report.exists() else []
            names.append([Path(f).name for f in figures])
        except (OSError, ValueError, AttributeError, TypeError) as err:
            raise DataFileError(f"{report}: not a readable eval.json ({err})") from None
    if not names[0] or any(n != names[0] for n in names):
        return None
    rows, cols = len(run_dirs), len(names[0])
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.3 * rows), squeeze=False)
    for r, run_dir in enumerate(run_dirs):
        for c, name in enumerate(names[0]):
            try:
                axes[r, c].imshow(plt.imread(Path(run_dir) / name))
            except (OSError, ValueError, SyntaxError) as err:
                plt.close(fig)
                raise DataFileError(f"{Path(run_dir) / name}: cannot be read as a figure ({err})") from None
            axes[r, c].axis("off")
        axes[r, 0].text(
            -0.04,
            0.5,
            _label(Path(run_dir)),
            transform=axes[r, 0].transAxes,
            rotation=90,
            va="center",
            ha="right",
            fontsize=10,
        )
    fig.tight_layout()
    save_figure(fig, path, dpi=80)
    plt.close(fig)
    return path


def plot_runs(run_dirs: Sequence[str | Path], out_dir: str | Path | None = None) -> list[Path]:
    """Write ``curves.png`` (return, episode length, success), ``curves_diagnostics.png`` (flow runs) and, when
    every run has the same evaluation figures, ``figures_grid.png`` tiling them; default out dir: the first run's."""
    runs = {_label(Path(d)): read_rows(d) for d in run_dirs}
    out = Path(out_dir or run_dirs[0])
    out.mkdir(parents=True, exist_ok=True)
    written = [training_curves(runs, out / "curves.png")]
    if any(key in row for rows in runs.values() for row in rows for key, _ in DIAGNOSTICS):
        written.append(diagnostic_curves(runs, out / "curves_diagnostics.png"))
    grid = figure_grid([Path(d) for d in run_dirs], out / "figures_grid.png")
    return written + ([grid] if grid else [])
