#!/usr/bin/env python
"""Fine-tuning on the two-way task from its clones: ``finetuning.md`` in this folder, written whole from
``finetuning.template.md`` and the committed runs (nothing typed in by hand):

    python docs/results/multimodal/finetuning.py [--add-runs runs/sweeps/finetune_point_mass_wall] [--check]

Rows: ``finetune/runs.csv`` (``refpo sweep finetune_point_mass_wall``, then ``refpo report`` of it); each run's
``eval.json`` (success and each way's share at N = 10 and N = 1, PPO: its mean action) and ``progress_eval.jsonl``
(the periodic evaluation's curves) under ``finetune/runs/``; the clones' ``eval.json`` beside this script.
``--add-runs`` appends the finished runs of a sweep dir not yet in the table and copies their small files.
"""

from __future__ import annotations

import functools
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from finetune_updates import update_text

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, read_rows, seeds_text
from refpo_warp.studies.reports.intervals import aggregate, improvement
from refpo_warp.studies.reports.results_page import main_args, write_page
from refpo_warp.utils.atomic_files import save_figure

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
SWEEP = ROOT / "configs" / "sweep" / "finetune_point_mass_wall.yaml"
RUNS_CSV = HERE / "finetune" / "runs.csv"
RUNS_DIR = HERE / "finetune" / "runs"
FIGURE = HERE / "finetune_curves.png"
TASK = "dmc_point_mass_wall"
CLONE_OF = {  # method label -> the clone folder (beside this script) its runs start from
    "refpo": "clone_flow",
    "refpo_adaptive": "clone_flow",
    "fpo": "clone_fpo",
    "fpo_pp": "clone_fpo_pp",
    "ppo": "clone_gauss",
}
SUCCESS_FLOOR = 0.5  # a run below this success has lost the task
MINORITY_FLOOR = 0.1  # a run whose rarer way is below this share of its passes keeps one way
MACHINE = "a 2-core AMD EPYC shared with other work"  # where the sweep ran (its runs record no machine)
COLOURS = {"refpo": "#1f77b4", "refpo_adaptive": "#17becf", "fpo": "#ff7f0e", "fpo_pp": "#9467bd", "ppo": "#2ca02c"}


# ------------------------------------------------------------------------------------------------ data
def methods() -> list[dict]:
    return load_yaml(SWEEP)["methods"]


def setting_of(label: str, n: int) -> str | None:
    """The eval.json setting of a method at N (PPO: its mean action, at N = 10 only)."""
    if label == "ppo":
        return "mean_action" if n == 10 else None
    return f"N={n}"


@functools.cache
def rows() -> tuple[dict, ...]:
    """The committed runs' rows (``finetune/runs.csv``), read once per process."""
    return tuple(read_rows(RUNS_CSV)) if RUNS_CSV.exists() else ()


def run_results(label: str) -> dict[int, dict]:
    """seed -> the run's eval.json results (a failed run: None)."""
    out: dict[int, dict] = {}
    for row in rows():
        if row["task"] != TASK or row["label"] != label:
            continue
        if row["status"] == "failed":
            out[int(row["seed"])] = {}
        elif row["status"] == "ok":
            out[int(row["seed"])] = json.loads((ROOT / row["run_dir"] / "eval.json").read_text())["results"]
    return out


def numbers(result: dict) -> dict[str, float]:
    """One evaluation setting's success, each way's share of the episodes, the rarer way's share of the passes and
    the return (a failed run: zeros)."""
    if not result:
        return {"success": 0.0, "left": 0.0, "right": 0.0, "rarer": 0.0, "return": 0.0, "episodes": 0}
    left, right = result["went_left_mean"], result["went_right_mean"]
    return {
        "success": result["success_mean"],
        "left": left,
        "right": right,
        "rarer": min(left, right) / (left + right) if left + right else 0.0,
        "return": result["return_mean"],
        "episodes": result["episodes"],
    }


def outcome(n: dict[str, float]) -> str:
    if n["success"] < SUCCESS_FLOOR:
        return "lost"
    return "one way" if n["rarer"] < MINORITY_FLOOR else "both ways"


def percent(e, digits: int = 0) -> str:
    return f"{100 * e.point:.{digits}f} % [{100 * e.low:.{digits}f}, {100 * e.high:.{digits}f}]"


def interval(values: list[float]):
    return aggregate({"m": np.asarray(values, dtype=float)[:, None]})["m"]["mean"]


# ------------------------------------------------------------------------------------------------ tables
MEASURED_CLONES = {  # clone, setting -> its setting in clones.json (the clones page's 500 episodes)
    ("clone_flow", "N=10"): "flow_N10",
    ("clone_flow", "N=1"): "flow_N1",
    ("clone_gauss", "mean_action"): "gauss_mean",
}


def clone_numbers(clone: str, setting: str) -> dict[str, float]:
    """A clone's numbers at ``setting``: the clones page's rollouts (clones.json) where it made them, else the
    clone's own evaluation (its eval.json, the pretrain run's)."""
    if (clone, setting) in MEASURED_CLONES:
        m = json.loads((HERE / "clones.json").read_text())["settings"][MEASURED_CLONES[clone, setting]]
        k = m["episodes"]
        return numbers(
            {
                "success_mean": m["success"] / k,
                "went_left_mean": m["left"] / k,
                "went_right_mean": m["right"] / k,
                "return_mean": float(np.mean(m["returns"])),
                "episodes": k,
            }
        )
    return numbers(json.loads((HERE / clone / "eval.json").read_text())["results"][setting])


def clone_row(label: str, setting: str) -> str:
    c = clone_numbers(CLONE_OF[label], setting)
    return (
        f"| its clone (`{CLONE_OF[label]}`) | {c['episodes']} episodes | {100 * c['success']:.0f} % | "
        f"{100 * c['left']:.0f} % | {100 * c['right']:.0f} % | {100 * c['rarer']:.0f} % | {c['return']:.0f} | "
        f"{outcome(c)} |"
    )


def method_table(n: int) -> str:
    head = (
        "| method | seeds | success [95 %] | left [95 %] | right [95 %] | rarer way among the passes [95 %] | "
        "return [95 %] | runs: both ways / one way / lost |"
    )
    lines = [head, "|---|---|---|---|---|---|---|---|"]
    for method in methods():
        label = method["label"]
        setting = setting_of(label, n)
        if setting is None:
            continue
        runs = run_results(label)
        if not runs:
            continue
        per = [numbers(r.get(setting, {}) if r else {}) for r in runs.values()]
        kinds = [outcome(p) for p in per]
        cells = [percent(interval([p[k] for p in per])) for k in ("success", "left", "right", "rarer")]
        ret = interval([p["return"] for p in per]).text()
        counts = " / ".join(str(kinds.count(k)) for k in ("both ways", "one way", "lost"))
        lines.append(f"| {method['name']} | {seeds_text(runs)} | {' | '.join(cells)} | {ret} | {counts} |")
        lines.append(clone_row(label, setting))
    return "\n".join(lines)


def per_run_table() -> str:
    lines = ["| method | seed | N = 10 (PPO: mean action): success, left, right | N = 1: success, left, right |"]
    lines.append("|---|---|---|---|")
    for method in methods():
        label = method["label"]
        for seed, results in sorted(run_results(label).items()):
            cells = []
            for n in (10, 1):
                setting = setting_of(label, n)
                if setting is None:
                    cells.append("--")
                    continue
                p = numbers(results.get(setting, {}) if results else {})
                text = f"{100 * p['success']:.0f} %, {100 * p['left']:.0f} %, {100 * p['right']:.0f} %"
                cells.append(text + f" ({outcome(p)})" if n == 10 else text)
            lines.append(f"| {method['name']} | {seed} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def comparison_table() -> str:
    """Each flow method's success against PPO's, and its rarer way's share against PPO's, by P(improvement)."""
    ppo = run_results("ppo")
    lines = ["| comparison | statistic | P(improvement) [95 %] | what it says |", "|---|---|---|---|"]
    for method in methods():
        label = method["label"]
        runs = run_results(label)
        if label == "ppo" or not runs or not ppo:
            continue
        for key, name in (("success", "success"), ("rarer", "rarer way among the passes")):
            x = np.array([[numbers(r.get("N=10", {}) if r else {})[key]] for r in runs.values()])
            y = np.array([[numbers(r.get("mean_action", {}) if r else {})[key]] for r in ppo.values()])
            p = improvement(x, y)
            if p.low > 0.5:
                says = f"{method['name'].split(' from')[0]} higher: the interval lies above 0.5"
            elif p.high < 0.5:
                says = "PPO higher: the interval lies below 0.5"
            else:
                says = "the interval holds 0.5: these seeds do not separate them"
            lines.append(f"| {method['name'].split(' from')[0]} over PPO | {name} (N = 10) | {p.text(2)} | {says} |")
    return "\n".join(lines)


def summary() -> str:
    """One line per method: its runs' outcomes at N = 10 (PPO: its mean action)."""
    lines = []
    for method in methods():
        label = method["label"]
        runs = run_results(label)
        if not runs:
            continue
        per = [numbers(r.get(setting_of(label, 10), {}) if r else {}) for r in runs.values()]
        kinds = [outcome(p) for p in per]
        lines.append(
            f"- **{method['name']}**: of its {len(per)} runs, {kinds.count('both ways')} kept both ways, "
            f"{kinds.count('one way')} one way and {kinds.count('lost')} lost the task; success "
            f"{percent(interval([p['success'] for p in per]))}."
        )
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ curves
def curves(label: str) -> dict[int, list[dict]]:
    out = {}
    for row in rows():
        if row["task"] == TASK and row["label"] == label and row["status"] == "ok":
            path = ROOT / row["run_dir"] / "progress_eval.jsonl"
            out[int(row["seed"])] = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return out


def warmup_iterations() -> int:
    """The critic's warm-up (``critic_warmup_iterations``, the actor held fixed), from a run's config."""
    row = next(r for r in rows() if r["status"] == "ok")
    return int(load_yaml(ROOT / row["run_dir"] / "config.yaml")["critic_warmup_iterations"])


def warmup_env_steps() -> int:
    """Env steps of the critic's warm-up, from a run's config."""
    row = next(r for r in rows() if r["status"] == "ok")
    cfg = load_yaml(ROOT / row["run_dir"] / "config.yaml")
    return warmup_iterations() * int(cfg["num_envs"]) * int(cfg["runner"]["num_steps_per_env"])


def run_folders() -> dict[str, tuple[str, list[Path]]]:
    """label -> (the method's name, its finished runs' folders)."""
    return {
        m["label"]: (
            m["name"],
            [ROOT / r["run_dir"] for r in rows() if r["label"] == m["label"] and r["status"] == "ok"],
        )
        for m in methods()
    }


def figure() -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for method in methods():
        label = method["label"]
        suffix = "" if label == "ppo" else "_N10"
        runs = curves(label)
        if not runs:
            continue
        steps = np.array([r["env_steps"] for r in next(iter(runs.values()))])
        success = np.array([[r[f"eval/success{suffix}"] for r in rows] for rows in runs.values()])
        left = np.array([[r[f"eval/went_left{suffix}"] for r in rows] for rows in runs.values()])
        right = np.array([[r[f"eval/went_right{suffix}"] for r in rows] for rows in runs.values()])
        passes = left + right
        share = np.divide(left, passes, out=np.full_like(left, np.nan), where=passes > 0)
        for ax, values in ((axes[0], success), (axes[1], share)):
            ax.plot(steps, np.nanmean(values, axis=0), color=COLOURS[label], label=method["name"])
            ax.fill_between(
                steps, np.nanmin(values, axis=0), np.nanmax(values, axis=0), color=COLOURS[label], alpha=0.15
            )
    warmup = warmup_env_steps()
    for ax in axes:
        ax.axvline(warmup, color="grey", lw=0.8, ls="--")
    axes[0].text(warmup, 0.5, " critic warm-up ends", color="grey", fontsize=7)
    axes[0].set_ylabel("success (N = 10; PPO: mean action)")
    axes[1].set_ylabel("left share of the passes")
    axes[1].axhline(0.5, color="k", lw=0.5, ls=":")
    for ax in axes:
        ax.set_xlabel("env steps of fine-tuning")
        ax.set_ylim(-0.02, 1.02)
    axes[0].legend(fontsize=7, loc="lower right")
    fig.suptitle("dmc_point_mass_wall, fine-tuned from clones: mean over seeds, band from the lowest to the highest")
    save_figure(fig, FIGURE, dpi=110, bbox_inches="tight")
    plt.close(fig)


# ------------------------------------------------------------------------------------------------ the page
def values() -> dict[str, object]:
    sweep = load_yaml(SWEEP)
    seeds = sorted({s for m in methods() for s in run_results(m["label"])})
    data = json.loads((HERE / "data" / "metadata.json").read_text())
    eval_envs = sweep["overrides"]["eval"]["num_envs"]
    return {
        "env_steps": f"{sweep['overrides']['total_env_steps']:,}",
        "eval_episodes": eval_envs,
        "seeds": seeds_text(seeds),
        "n_seeds": len(seeds),
        "data_episodes": data["total_episodes"],
        "left_share": data["refpo"]["policy"]["left_share"],
        "summary": summary(),
        "updates": update_text(run_folders(), warmup_iterations()),
        "warmup": f"{warmup_env_steps():,}",
        "machine": MACHINE,
        "success_floor": f"{100 * SUCCESS_FLOOR:.0f} %",
        "minority_floor": f"{100 * MINORITY_FLOOR:.0f} %",
        "table_10": method_table(10),
        "table_1": method_table(1),
        "per_run": per_run_table(),
        "comparisons": comparison_table(),
    }


def main() -> None:
    parser = main_args(__doc__.splitlines()[0])
    parser.add_argument("--add-runs", nargs="*", default=[], type=Path, help="sweep dirs whose finished runs to add")
    args = parser.parse_args()
    for sweep_dir in args.add_runs:
        added = append_runs(sweep_dir, RUNS_CSV, RUNS_DIR, ROOT)
        print(f"{RUNS_CSV.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")
    if not args.check:
        figure()
    same = write_page(HERE / "finetuning.template.md", values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


if __name__ == "__main__":
    main()
