"""tables.py --dmc's figures: dmc_curves.png (fine-tuned and from-scratch evaluation curves side by side) and
dmc_remedies.png (ReFPO's fine-tuning beside each remedy tried against its collapse)."""

from __future__ import annotations

from pathlib import Path

from dmc_runs import eval_curve, final_returns, return_targets, run_groups
from study_layout import DMC_KEPT, DMC_METHODS, DMC_TASKS


# ------------------------------------------------------------------------------------------------ figures
def dmc_curves(path: Path, remedies: bool = False) -> Path | None:
    """The periodic evaluation return over env steps, seeds' mean with their range shaded, the data's return and
    PPO's full-profile final as dotted lines. One panel per (task, method): fine-tuned from the clone (solid) beside
    from scratch (dashed); with ``remedies``, one panel per task with a variant, ReFPO's fine-tuning beside each
    variant tried against its collapse."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    from refpo_warp.evaluation.curves import seed_stats
    from refpo_warp.utils.atomic_files import save_figure

    names = {label: what for label, _, what in DMC_METHODS}
    if remedies:
        tried = [(task, [g for g in run_groups(task) if g[0] != "scratch" and g[2] == "refpo"]) for task in DMC_TASKS]
        panels = [
            (task, groups, "ReFPO from the flow clone, remedies tried") for task, groups in tried if len(groups) > 1
        ]
    else:
        panels = [
            (task, [g for g in run_groups(task) if g[1] == base], names[base])
            for task in DMC_TASKS
            for base in ("refpo", "refpo_onestep", "ppo")
        ]
    if not panels:
        return None
    cols = 1 if remedies else 3
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.4 * cols * (2.0 if remedies else 1), 3.3 * rows), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (task, groups, title) in zip(axes.flat, panels):
        data, ppo_final = return_targets(task)
        for i, (start, _, base, what, runs) in enumerate(groups):
            curves = [eval_curve(run) for run in runs]
            if start != "scratch":  # the clone's own evaluation at 0 env steps starts the curve
                first = final_returns(
                    DMC_KEPT / task / ("clone_ppo" if base == "ppo" else "clone_refpo") / "eval.json"
                )[0]
                curves = [([0, *x], [first, *y]) for x, y in curves]
            steps, mean, low, high = seed_stats(curves)
            color = "0.35" if start == "scratch" else colors[i % len(colors)]
            name = f"{what}, from {start}" if remedies or start == "scratch" else f"from {start}"
            ax.plot(steps, mean, color=color, ls="--" if start == "scratch" else "-", lw=1.6, label=name)
            ax.fill_between(steps, low, high, color=color, alpha=0.1, lw=0)
        ax.axhline(data, color="tab:green", ls=":", lw=1, label="the data's return")
        ax.axhline(ppo_final, color="black", ls=":", lw=1, label="PPO from scratch, full profile")
        ax.set_title(f"{task}: {title}", fontsize=9)
        ax.set_xlabel("env steps")
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda x, _: f"{x / 1000:.0f}k"))
        ax.set_ylim(0, 1000)
        ax.grid(alpha=0.3)
        if remedies:  # many lines: the legend beside the panel
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        else:
            ax.legend(fontsize=6.5, loc="best")
    for ax in axes.flat[len(panels) :]:
        ax.set_visible(False)
    axes[0, 0].set_ylabel("return (N = 10; PPO: mean action)")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)
    return path
