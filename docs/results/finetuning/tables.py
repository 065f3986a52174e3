"""The tables of docs/results/finetuning/README.md, from the study's files (gridworld.sh, dmc.sh).

    python docs/results/finetuning/tables.py [--runs runs/finetuning/gridworld] [--keep]
    python docs/results/finetuning/tables.py --dmc

``--dmc``: keeps the DMC runs' small files (from runs/finetuning/dmc and runs/sweeps, where present) in dmc/,
normalizers_updated/ and scratch/, writes the DMC table (fine-tuned and from-scratch runs at the same env steps, mean
with a 95 % stratified bootstrap interval over seeds), dmc_curves.png (their evaluation curves side by side) and
dmc_remedies.png (ReFPO's fine-tuning beside each remedy tried against its collapse).

Reads each run's eval.json (the dataset's own numbers from the clone's eval.json), writes the table between the
README's markers, and with ``--keep`` copies each run's small files (config.yaml, eval.json, progress.jsonl) and the
dataset's metadata.json into docs/results/finetuning/gridworld/, so the numbers outlive the machine; the table is then
read from there. For the Gaussian clone it also rolls the clone out again and counts where its unfinished episodes
stand when the 200-step time-out ends them (the row, relative to the middle row).
"""

from __future__ import annotations

import argparse
import csv
import functools
import json
import shutil
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
KEPT = HERE / "gridworld"
BEGIN, END = (
    "<!-- gridworld table: begin (python docs/results/finetuning/tables.py) -->",
    "<!-- gridworld table: end -->",
)
DMC_BEGIN, DMC_END = (
    "<!-- dmc table: begin (python docs/results/finetuning/tables.py --dmc) -->",
    "<!-- dmc table: end -->",
)
DMC_KEPT = HERE / "dmc"  # the demonstrator, data and clones, and the fine-tuning runs (clone_normalizer=keep)
UPDATED_KEPT = HERE / "normalizers_updated"  # fine-tuning runs whose normalisers followed the rollouts, remedies tried
SCRATCH_KEPT = HERE / "scratch"  # from scratch at the fine-tuning runs' env steps
DMC_TASKS = ("dmc_point_mass", "dmc_reacher_easy")
DMC_METHODS = (  # (sweep label, the method it varies, name); the variants are the remedies tried for ReFPO's collapse
    ("refpo", "refpo", "ReFPO"),
    ("refpo_action_noise_std0.02", "refpo", "ReFPO, action noise 0.02"),
    ("refpo_action_noise_std0.05", "refpo", "ReFPO, action noise 0.05"),
    ("refpo_lr1e-4", "refpo", "ReFPO, learning rate 1e-4"),
    ("refpo_adaptive", "refpo", "ReFPO, adaptive lambda"),
    ("refpo_aspo", "refpo", "ReFPO, ASPO trust region"),
    ("refpo_onestep", "refpo_onestep", "refpo_onestep"),
    ("refpo_onestep_action_noise_std0.02", "refpo_onestep", "refpo_onestep, action noise 0.02"),
    ("refpo_onestep_action_noise_std0.05", "refpo_onestep", "refpo_onestep, action noise 0.05"),
    ("ppo", "ppo", "PPO"),
    ("ppo_lr1e-4", "ppo", "PPO, learning rate 1e-4"),
)
# (where the runs are kept, the sweeps they come from by task name, how they started)
DMC_SOURCES = (
    (DMC_KEPT, ("finetune_{}", "finetune_remedies_keep_{}"), "the {clone}"),
    (
        UPDATED_KEPT,
        ("finetune_normupdate_{}", "finetune_floor_{}", "finetune_remedies_{}"),
        "the {clone}, normalisers updated",
    ),
    (SCRATCH_KEPT, ("finetune_scratch",), "scratch"),
)
DMC_FIGURE, REMEDIES_FIGURE = HERE / "dmc_curves.png", HERE / "dmc_remedies.png"
FROM_SCRATCH = HERE.parent / "cpu_dmc" / "per_task.csv"  # PPO's final return at the full CPU profile (1M env steps)
ROWS = [  # (run folder, what it is)
    ("clone_flow", "flow clone (refpo pretrain algo=refpo)"),
    ("clone_gauss", "Gaussian clone (refpo pretrain algo=ppo)"),
    ("refpo_from_flow", "ReFPO fine-tuned from the flow clone"),
    ("fpo_from_flow", "FPO fine-tuned from the flow clone"),
    ("ppo_from_gauss", "PPO fine-tuned from the Gaussian clone"),
]
FILES = ("config.yaml", "eval.json", "progress.jsonl")


def keep(runs: Path) -> None:
    for name, _ in ROWS:
        for file in FILES:
            if (runs / name / file).exists():
                (KEPT / name).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(runs / name / file, KEPT / name / file)
    if (runs / "data" / "metadata.json").exists():
        (KEPT / "data").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(runs / "data" / "metadata.json", KEPT / "data" / "metadata.json")


def timeout_rows(run: Path, episodes: int = 200) -> Counter:
    """Where the Gaussian clone's time-outs stand: the row (y) of each episode the 200-step time-out ended."""
    import torch

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    resolved = load_run(run, {"device": "cpu"})
    cfg = resolved.cfg
    env = make_env(resolved.task, num_envs=episodes, device="cpu", seed=cfg["seed"] + 10_000, **cfg["env"])
    _, runner = build_runner(resolved, None, env=env)
    load_latest(runner, run, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device="cpu")
    obs, ended, rows = env.reset(), torch.zeros(episodes, dtype=torch.bool), Counter()
    with torch.inference_mode():
        for _ in range(int(env.max_episode_length)):
            before = env.positions.clone()
            obs, _, dones, extras = env.step(actor(obs))
            timed_out = extras["time_outs"] & ~ended
            for i in timed_out.nonzero().flatten().tolist():
                rows[int(before[i, 1])] += 1
            ended |= dones
            if bool(ended.all()):
                break
    return rows


def table(source: Path, runs: Path) -> str:
    lines = ["| policy | N | success | top share | bottom share | episode length |", "|---|---|---|---|---|---|"]
    clone = json.loads((source / "clone_flow" / "eval.json").read_text())
    d = clone["dataset"]
    lines.append(
        f"| demonstrations (scripted, {d['episodes']} episodes) | - | {d['success_rate']:.3f} | "
        f"{d['top_share']:.3f} | {d['bottom_share']:.3f} | {d['length_mean']:.2f} |"
    )
    notes = []
    for name, what in ROWS:
        path = source / name / "eval.json"
        if not path.exists():
            lines.append(f"| {what} | - | not run | | | |")
            continue
        results = json.loads(path.read_text())["results"]
        for setting in ("N=1", "N=10", "mean_action"):
            if setting in results:
                r = results[setting]
                n = setting[2:] if setting.startswith("N=") else "mean action"
                lines.append(
                    f"| {what} | {n} | {r['success_rate']:.3f} | {r['top_share']:.3f} | "
                    f"{r['bottom_share']:.3f} | {r['length_mean']:.1f} |"
                )
    if (runs / "clone_gauss" / "model_0.pt").exists():
        rows = timeout_rows(runs / "clone_gauss")
        shown = ", ".join(f"row {y}: {k}" for y, k in sorted(rows.items()))
        notes.append(
            f"\nThe Gaussian clone's time-outs (200 episodes from fresh starts, mean action), by the row they "
            f"end in (12 is the middle; the demonstrator's two-mode band is rows 9-15): {shown or 'none'}."
        )
    return "\n".join(lines) + "\n" + "\n".join(notes)


def _final(path: Path) -> tuple[float, float | None]:
    """(N = 10 or the Gaussian's mean-action return, N = 1 return or None) of an eval.json."""
    results = json.loads(path.read_text())["results"]
    if "mean_action" in results:
        return results["mean_action"]["return_mean"], None
    return results["N=10"]["return_mean"], results["N=1"]["return_mean"]


def _curve(run: Path) -> tuple[list[float], list[float]]:
    """(env steps, return) of the periodic evaluations: N = 10 for a flow, the mean action for PPO."""
    from refpo_warp.evaluation.curves import series
    from refpo_warp.runner.progress import read_rows

    rows = read_rows(run)
    steps, values = series(rows, "eval/return_N10")
    return (steps, values) if steps else series(rows, "eval/return")


def first_reaching(curve: tuple[list[float], list[float]], value: float) -> float | None:
    """Env steps at the first periodic evaluation of ``curve`` (``_curve``) whose return reaches ``value``."""
    return next((s for s, v in zip(*curve) if v >= value), None)


def keep_dmc(runs: Path, sweeps: Path) -> None:
    """The DMC study's small files (each stage's and each finished run's config, eval.json and progress rows), from
    runs/finetuning/dmc and the sweeps of DMC_SOURCES into their folders here."""
    for task in DMC_TASKS:
        stages = [(runs / task / name, DMC_KEPT / task / name) for name in ("demonstrator", "clone_refpo", "clone_ppo")]
        for kept, names, _ in DMC_SOURCES:
            for name in names:
                stages += [
                    (run, kept / task / run.parent.name / run.name)
                    for run in sorted((sweeps / name.format(task[4:]) / task).glob("*/seed*"))
                ]
        for src, dst in stages:
            if (src / "eval.json").exists():
                dst.mkdir(parents=True, exist_ok=True)
                for file in FILES:
                    if (src / file).exists():
                        shutil.copyfile(src / file, dst / file)
        if (runs / task / "data" / "metadata.json").exists():
            (DMC_KEPT / task / "data").mkdir(parents=True, exist_ok=True)
            shutil.copyfile(runs / task / "data" / "metadata.json", DMC_KEPT / task / "data" / "metadata.json")


def _interval(values: list[float]) -> str:
    """Mean [95 % stratified-bootstrap interval] over seeds (rliable), then each seed's value."""
    import numpy as np

    from refpo_warp.sweeps.intervals import aggregate

    est = aggregate({"x": np.asarray(values, float).reshape(-1, 1)})["x"]["mean"]
    return f"{est.point:.0f} [{est.low:.0f}, {est.high:.0f}] ({', '.join(f'{v:.0f}' for v in values)})"


def _steps(values: list[float | None]) -> str:
    return ", ".join("-" if v is None else f"{v / 1000:.0f}k" for v in values)


def _groups(task: str):
    """(start, label, base, what, seed runs) of the task's fine-tuned and from-scratch groups, in the table's order:
    per method, its runs from the clone, with the normalisers updated, its variants, from scratch."""
    for label, base, what in DMC_METHODS:
        clone = "Gaussian clone" if base == "ppo" else "flow clone"
        for kept, _, start in DMC_SOURCES:
            runs = sorted((kept / task / label).glob("seed*/eval.json"))
            if runs:
                yield start.format(clone=clone), label, base, what, [r.parent for r in runs]


@functools.cache
def _cpu_dmc() -> dict[tuple[str, str], dict]:
    """The committed cpu_dmc rows by (task, label)."""
    return {(r["task"], r["label"]): r for r in csv.DictReader(FROM_SCRATCH.open())}


def _targets(task: str) -> tuple[float | None, float]:
    """The data's return and PPO's from-scratch final return at the full CPU profile (cpu_dmc)."""
    clone = DMC_KEPT / task / "clone_refpo" / "eval.json"
    data = json.loads(clone.read_text())["dataset"]["return_mean"] if clone.exists() else None
    return data, float(_cpu_dmc()[(task, "ppo")]["return_multi_mean"])


def dmc_table() -> str:
    header = (
        "| task | method, from | return N = 10 (PPO: mean action), mean [95 % CI] (seeds) | N = 1 | "
        "env steps to the data's return | to PPO's full-profile final |"
    )
    lines = [header, "|---|---|---|---|---|---|"]
    for task in DMC_TASKS:
        root = DMC_KEPT / task
        if not (root / "data" / "metadata.json").exists():
            lines.append(f"| {task} | not run yet | | | | |")
            continue
        meta = json.loads((root / "data" / "metadata.json").read_text())["refpo"]
        data, ppo_final = _targets(task)
        demo = Path(meta["policy"]["checkpoint"]).stem
        lines.append(
            f"| {task} | demonstrations: PPO's {demo}, mean action + noise {meta['policy']['action_noise_std']:g} "
            f"| {data:.0f} over the dataset's episodes | | | |"
        )
        for name, what in (("clone_refpo", "flow clone (0 env steps)"), ("clone_ppo", "Gaussian clone (0 env steps)")):
            if (root / name / "eval.json").exists():
                multi, one = _final(root / name / "eval.json")
                lines.append(f"| {task} | {what} | {multi:.0f} | {'-' if one is None else f'{one:.0f}'} | | |")
        for start, _, _, what, runs in _groups(task):
            finals = [_final(run / "eval.json") for run in runs]
            one = [f[1] for f in finals if f[1] is not None]
            curves = [_curve(run) for run in runs]
            reach = [_steps([first_reaching(c, target) for c in curves]) for target in (data, ppo_final)]
            lines.append(
                f"| {task} | {what}, from {start} | {_interval([f[0] for f in finals])} | "
                f"{_interval(one) if one else '-'} | {reach[0]} | {reach[1]} |"
            )
    return "\n".join(lines) + "\n"


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
        panels = [(task, [g for g in _groups(task) if g[0] != "scratch" and g[2] == "refpo"]) for task in DMC_TASKS]
        panels = [
            (task, groups, "ReFPO from the flow clone, remedies tried") for task, groups in panels if len(groups) > 1
        ]
    else:
        panels = [
            (task, [g for g in _groups(task) if g[1] == base], names[base])
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
        data, ppo_final = _targets(task)
        for i, (start, _, base, what, runs) in enumerate(groups):
            curves = [_curve(run) for run in runs]
            if start != "scratch":  # the clone's own evaluation at 0 env steps starts the curve
                first = _final(DMC_KEPT / task / ("clone_ppo" if base == "ppo" else "clone_refpo") / "eval.json")[0]
                curves = [([0, *x], [first, *y]) for x, y in curves]
            steps, mean, low, high = seed_stats(curves)
            color = "0.35" if start == "scratch" else colors[i % len(colors)]
            name = f"{what}, from {start}" if remedies or start == "scratch" else f"from {start}"
            ax.plot(steps, mean, color=color, ls="--" if start == "scratch" else "-", lw=1.6, label=name)
            ax.fill_between(steps, low, high, color=color, alpha=0.1, lw=0)
        if data is not None:
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


def write_between(begin: str, end: str, text: str) -> None:
    readme = HERE / "README.md"
    page = readme.read_text()
    head, rest = page.split(begin)
    _, tail = rest.split(end)
    readme.write_text(f"{head}{begin}\n\n{text}\n{end}{tail}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("runs/finetuning/gridworld"))
    parser.add_argument("--keep", action="store_true")
    parser.add_argument("--dmc", action="store_true", help="the DMC study's table (its files kept first)")
    args = parser.parse_args()
    if args.dmc:
        keep_dmc(Path("runs/finetuning/dmc"), Path("runs/sweeps"))
        text = dmc_table()
        write_between(DMC_BEGIN, DMC_END, text)
        print(text)
        print(dmc_curves(DMC_FIGURE), dmc_curves(REMEDIES_FIGURE, remedies=True))
        return
    if args.keep:
        keep(args.runs)
    source = KEPT if (KEPT / "clone_flow" / "eval.json").exists() else args.runs
    text = table(source, args.runs)
    write_between(BEGIN, END, text)
    print(text)


if __name__ == "__main__":
    main()
