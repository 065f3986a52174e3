"""Training-curve figures from ``progress.jsonl``: returns (with the 10-step/1-step gap) and flow diagnostics.

Several runs can share one figure (e.g. FPO vs ReFPO): each run dir is one coloured line.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DIAGNOSTICS = (
    ("Flow/ratio_max", "max ratio per update"),
    ("Flow/clip_fraction", "clip fraction"),
    ("Flow/explosion_rate", "Explosion Rate (per action)"),
    ("Flow/straightness_error", "Straightness Error"),
)


def read_progress(run_dir: str | Path) -> list[dict]:
    path = Path(run_dir) / "progress.jsonl"
    if not path.exists():
        raise FileNotFoundError(f"{path} not found: train with tools/train.py first")
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _series(rows: list[dict], key: str) -> tuple[list[float], list[float]]:
    pts = [(r["env_steps"], r[key]) for r in rows if key in r]
    return [p[0] for p in pts], [p[1] for p in pts]


def _label(run_dir: Path) -> str:
    return f"{run_dir.parent.name}/{run_dir.name}" if run_dir.parent.name else run_dir.name


def return_curves(runs: dict[str, list[dict]], path: Path, low: str = "eval/return_N1",
                  high: str = "eval/return_N10") -> Path:  # fmt: skip
    """Evaluation returns at N=10 and N=1 over env steps, the gap between them shaded (training return if absent)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for (label, rows), color in zip(runs.items(), colors * 4):
        x_hi, y_hi = _series(rows, high)
        x_lo, y_lo = _series(rows, low)
        if x_hi and x_lo and x_hi == x_lo:
            ax.plot(x_hi, y_hi, color=color, lw=1.8, label=f"{label} (10-step)")
            ax.plot(x_lo, y_lo, color=color, lw=1.0, ls="--", label=f"{label} (1-step)")
            ax.fill_between(x_hi, y_lo, y_hi, color=color, alpha=0.2)
        else:
            x, y = _series(rows, "eval/return")
            if not x:
                x, y = _series(rows, "reward_mean")
            ax.plot(x, y, color=color, lw=1.5, label=label)
    ax.set_xlabel("env steps")
    ax.set_ylabel("episode return")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def diagnostic_curves(runs: dict[str, list[dict]], path: Path) -> Path:
    """Ratio spikes, clip fraction, Explosion Rate and Straightness Error per update (paper §4.2 diagnostics)."""
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    for (key, title), ax in zip(DIAGNOSTICS, axes.flat):
        for label, rows in runs.items():
            x, y = _series(rows, key)
            if x:
                ax.plot(x, y, lw=1.0, label=label)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0, 0].set_yscale("log")
    for ax in axes[1]:
        ax.set_xlabel("env steps")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def figure_grid(run_dirs: list[Path], path: Path) -> Path | None:
    """Tile the evaluation figures of several runs (rows: runs, columns: figures listed in their eval.json)."""
    names = []
    for run_dir in run_dirs:
        report = Path(run_dir) / "eval.json"
        figures = json.loads(report.read_text()).get("figures", []) if report.exists() else []
        names.append([Path(f).name for f in figures])
    if not names[0] or any(n != names[0] for n in names):
        return None
    rows, cols = len(run_dirs), len(names[0])
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.3 * rows), squeeze=False)
    for r, run_dir in enumerate(run_dirs):
        for c, name in enumerate(names[0]):
            axes[r, c].imshow(plt.imread(Path(run_dir) / name))
            axes[r, c].axis("off")
        axes[r, 0].text(-0.04, 0.5, _label(Path(run_dir)), transform=axes[r, 0].transAxes, rotation=90,
                        va="center", ha="right", fontsize=10)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def plot_runs(run_dirs: list[str | Path], out_dir: str | Path | None = None) -> list[Path]:
    """Write ``curves_return.png``, ``curves_diagnostics.png`` (flow runs) and, when every run has the same
    evaluation figures, ``figures_grid.png`` tiling them; default out dir: the first run's."""
    runs = {_label(Path(d)): read_progress(d) for d in run_dirs}
    out = Path(out_dir or run_dirs[0])
    out.mkdir(parents=True, exist_ok=True)
    written = [return_curves(runs, out / "curves_return.png")]
    if any(key in row for rows in runs.values() for row in rows for key, _ in DIAGNOSTICS):
        written.append(diagnostic_curves(runs, out / "curves_diagnostics.png"))
    grid = figure_grid([Path(d) for d in run_dirs], out / "figures_grid.png")
    return written + ([grid] if grid else [])
