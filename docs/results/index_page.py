#!/usr/bin/env python
"""The results index, docs/results/README.md, from README.template.md and the committed files it reads:

    python docs/results/index_page.py [--check]

- the named sweeps' table: every ``configs/sweep/*.yaml`` expanded as ``refpo sweep --dry-run`` expands it
  (``refpo_warp.studies.grid.spec.load_sweep``), each (task, method)'s env steps resolved as ``refpo train`` resolves
  them;
- the sweep's constants the page names (Ray's retries of a lost task, the stop's grace) from their modules;
- the CPU-scale reproduction from ``cpu_dmc/runs.csv`` (one row per run): per task and method the mean over the seeds
  the file holds with its 95 % stratified-bootstrap interval (``refpo_warp/studies/reports/intervals.py``), the
  diagnostics' means, the Appendix C means, and which of the paper's directions hold, counted over the (task, seed)
  pairs, in words chosen here from the numbers.

The helpers for intervals, runs.csv rows and profiles are ``docs/results/results_reading.py``'s (imported from beside
this file).
"""

from __future__ import annotations

import statistics
import sys
from pathlib import Path
from typing import TYPE_CHECKING

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from results_reading import (  # noqa: E402  (docs/results/results_reading.py)
    ROOT,
    count_text,
    estimate,
    method_names,
    number,
    read_csv,
    short,
    steps_text,
)

from refpo_warp.studies.reports.committed_runs import seeds_text  # noqa: E402
from refpo_warp.studies.reports.results_page import main_args, write_page  # noqa: E402
from refpo_warp.utils.errors import DataFileError  # noqa: E402

if TYPE_CHECKING:  # imported where used: numpy's import is the cost of a page that needs no interval
    from refpo_warp.studies.reports.intervals import Estimate

TEMPLATE = HERE / "README.template.md"
CPU_DMC = HERE / "cpu_dmc" / "runs.csv"
# where each sweep's committed results are (relative to this page)
PAGES = {
    "cpu_dmc": "[cpu_dmc/](cpu_dmc/report.md), below",
    "cpu_reflow_pairs": "[one_step/](one_step/README.md)",
    "cpu_fpo_pp": "[fpo_pp/](fpo_pp/README.md)",
    "cpu_onestep": "[one_step/search.md](one_step/search.md)",
    "cpu_humanoid": "[../humanoid.md](../humanoid.md)",
    "finetune_point_mass": "[finetuning/](finetuning/README.md)",
    "finetune_point_mass_wall": "[multimodal/finetuning.md](multimodal/finetuning.md)",
    "finetune_reacher_easy": "[finetuning/](finetuning/README.md)",
    "finetune_scratch": "[finetuning/](finetuning/README.md)",
    "scratch_point_mass_wall": "[multimodal/scratch.md](multimodal/scratch.md)",
    "trend_8x": "[trend/](trend/README.md)",
    "paper_dmc": "not run (CUDA)",
}
LABELS = ("ppo", "fpo", "refpo")
ONE_STEP_NEAR = 0.75  # "ReFPO's 1-step ≈ 10-step" for a run: its 1-step return at least this fraction of its 10-step


# ------------------------------------------------------------------------------------------------ sweeps
def _steps(sweep) -> list[int]:
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.studies.grid.spec import device_type

    dtype = device_type(sweep.device) if sweep.device != "auto" else "cpu"
    out = set()
    for task in sweep.tasks:
        for method in sweep.methods:
            cfg = resolve_config({"task": task, "algo": method.algo, **method.overrides}, device_type=dtype)
            steps = (
                cfg["total_env_steps"] or cfg["max_iterations"] * cfg["num_envs"] * cfg["runner"]["num_steps_per_env"]
            )
            out.add(int(steps))
    return sorted(out)


def sweeps() -> tuple[str, dict]:
    from refpo_warp.studies.grid.spec import load_sweep

    lines = [
        "| sweep | its description | methods (labels) | tasks | seeds | device | env steps a run | runs | results |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    paper: dict | None = None
    for path in sorted((ROOT / "configs" / "sweep").glob("*.yaml")):
        sweep = load_sweep(path.stem)
        steps = _steps(sweep)
        steps_cell = steps_text(steps[0]) + (f"-{steps_text(steps[-1])}" if len(steps) > 1 else "")
        lines.append(
            f"| `{sweep.name}` | {sweep.description} | {', '.join(m.label for m in sweep.methods)} | "
            f"{', '.join(short(t) for t in sweep.tasks)} | {seeds_text(sweep.seeds)} | {sweep.device} | {steps_cell} | "
            f"{len(sweep.runs)} | {PAGES.get(sweep.name, '-')} |"
        )
        if sweep.name == "paper_dmc":
            paper = {"runs": len(sweep.runs), "steps": " or ".join(steps_text(s) for s in steps)}
    if paper is None:
        raise DataFileError("configs/sweep/ has no paper_dmc.yaml (the paper's sweep, whose runs the page counts)")
    return "\n".join(lines), paper


def cuda_iteration_steps() -> str:
    from results_reading import profile

    cfg = profile("dmc_cartpole_balance", "ppo", "cuda")
    return f"{cfg['num_envs'] * cfg['runner']['num_steps_per_env']:,}"


# ------------------------------------------------------------------------------------------------ cpu_dmc
def cpu_runs() -> dict[str, dict[str, dict[int, dict]]]:
    """method label -> task -> seed -> the run's row (numbers as floats, None where empty) of the finished runs."""
    out: dict[str, dict[str, dict[int, dict]]] = {}
    for r in read_csv(CPU_DMC):
        if r["status"] != "ok":
            continue
        text = ("task", "label", "status", "note", "run_dir", "headline", "health")  # the columns that are not numbers
        row = {k: number(v) for k, v in r.items() if k not in text}
        out.setdefault(r["label"], {}).setdefault(r["task"], {})[int(r["seed"])] = row
    return out


def _mean(values) -> float:
    return statistics.fmean(values)


def _diag(value: float | None) -> str:
    if value is None:
        return "--"
    return "0" if value == 0 else (f"{value:.2f}" if value >= 0.01 else f"{value:.1e}")


def _pooled(runs: dict[str, dict[int, dict]], key: str) -> Estimate:
    """The method's (seeds x tasks) scores pooled: the mean with its stratified-bootstrap interval (rliable)."""
    import numpy as np

    from refpo_warp.studies.reports.intervals import aggregate

    tasks = sorted(runs)
    n = min(len(runs[t]) for t in tasks)
    matrix = np.array([[runs[t][sorted(runs[t])[i]][key] for t in tasks] for i in range(n)])
    return aggregate({"x": matrix})["x"]["mean"]


def cpu_table(data) -> tuple[str, str]:
    lines = [
        "| task | method | N = 10 return | N = 1 return | Straightness | Explosion (per action) |",
        "|---|---|---|---|---|---|",
    ]
    tasks = sorted({t for by_task in data.values() for t in by_task})
    labels = [label for label in LABELS if label in data]
    names = method_names(CPU_DMC)
    for task in tasks:
        for label in labels:
            runs = data[label].get(task, {})
            if not runs:
                continue
            rows = list(runs.values())
            one_cell = estimate([r["return_1"] for r in rows]) if all(r["return_1"] is not None for r in rows) else "--"
            straight = [r["straightness"] for r in rows if r["straightness"] is not None]
            explosion = [r["explosion"] for r in rows if r["explosion"] is not None]
            lines.append(
                f"| {short(task)} | {names.get(label, label)} | {estimate([r['return_multi'] for r in rows])} | "
                f"{one_cell} | "
                f"{_diag(_mean(straight)) if straight else '--'} | {_diag(_mean(explosion)) if explosion else '--'} |"
            )
    pooled_runs = {}
    for label in labels:
        runs = data[label]
        if not all(runs.get(t) for t in tasks):
            continue
        rows = [r for t in tasks for r in runs[t].values()]
        pooled_runs[label] = len(rows)
        multi = _pooled(runs, "return_multi")
        one = _pooled(runs, "return_1") if all(r["return_1"] is not None for r in rows) else None
        straight = [r["straightness"] for r in rows if r["straightness"] is not None]
        explosion = [r["explosion"] for r in rows if r["explosion"] is not None]
        lines.append(
            f"| **all {len(tasks)}** | {names.get(label, label)} | "
            f"{multi.text()} | "
            + (one.text() if one else "--")
            + f" | {_diag(_mean(straight)) if straight else '--'} | {_diag(_mean(explosion)) if explosion else '--'} |"
        )
    seeds = sorted({s for by_task in data.values() for runs in by_task.values() for s in runs})
    counts = sorted(set(pooled_runs.values()))
    note = (
        f"Cells: the mean over the seeds ({seeds_text(seeds)}) with its 95 % stratified-bootstrap interval; the "
        f'"all {len(tasks)}" rows pool each method\'s {" or ".join(map(str, counts))} runs over the tasks (resampled '
        "within each task), as the paper's table pools tasks; Straightness and Explosion: the mean over the runs. "
        "`cpu_dmc/report.md` is `refpo report`'s table of the first seeds as made (mean ± population std, the "
        "paper's form); `cpu_dmc/README.md` compares the methods over every seed with probabilities of improvement."
    )
    return "\n".join(lines), note


def _range(values) -> str:
    return f"{min(values):.2f}-{max(values):.2f}"


def verdict(k: int, n: int) -> str:
    if k == n:
        return f"holds in {count_text(k, n)}"
    if k == 0:
        return f"does not hold in any of {n}"
    return f"holds in {k} of {n}" if k > n / 2 else f"holds in only {k} of {n}"


def compare(a: float, b: float) -> str:
    return "lower" if a < b else ("higher" if a > b else "level")


def directions(data) -> tuple[str, str, str]:
    """The Appendix C sentence, what the directions are counted over, and the bullets: each of the paper's directions
    at this scale, counted over the (task, seed) pairs where both methods have a finished run."""
    fpo, refpo, ppo = data.get("fpo", {}), data.get("refpo", {}), data.get("ppo", {})
    tasks = sorted(set(fpo) & set(refpo))
    pairs = [(t, s) for t in tasks for s in sorted(set(fpo[t]) & set(refpo[t]))]
    n = len(pairs)
    if not n:
        return "", "no (task, seed) pair with both FPO and ReFPO runs yet", ""
    F = {p: fpo[p[0]][p[1]] for p in pairs}
    R = {p: refpo[p[0]][p[1]] for p in pairs}

    def mean_of(runs, key, where=pairs):
        return _mean(runs[p][key] for p in where)

    appendix = (
        f"Appendix C (the {n} pairs' runs of each): Jacobian explosion rate FPO {mean_of(F, 'jac_expl'):.3f} against "
        f"ReFPO {mean_of(R, 'jac_expl'):.3f}, mean Jacobian spectral norm {mean_of(F, 'jac_norm_mean'):.2f} against "
        f"{mean_of(R, 'jac_norm_mean'):.2f} (its 95th percentile {mean_of(F, 'jac_norm_p95'):.2f} against "
        f"{mean_of(R, 'jac_norm_p95'):.2f}), ratio explosion {mean_of(F, 'ratio_expl'):.1e} against "
        f"{mean_of(R, 'ratio_expl'):.1e}."
    )
    bullets = []
    # 1. Straightness
    k = sum(R[p]["straightness"] < F[p]["straightness"] for p in pairs)
    bullets.append(
        f"- **Lower Straightness Error for ReFPO than FPO: {verdict(k, n)}** (ReFPO "
        f"{_range([R[p]['straightness'] for p in pairs])} against FPO {_range([F[p]['straightness'] for p in pairs])})."
    )
    # 2. Explosion
    lower = sum(R[p]["explosion"] < F[p]["explosion"] for p in pairs)
    both_zero = sum(R[p]["explosion"] == 0 == F[p]["explosion"] for p in pairs)
    refpo_zero = sum(R[p]["explosion"] == 0 for p in pairs)
    jac_lower = sum(R[p]["jac_expl"] < F[p]["jac_expl"] for p in pairs)
    jf, jr = mean_of(F, "jac_expl"), mean_of(R, "jac_expl")
    nf, nr = mean_of(F, "jac_norm_mean"), mean_of(R, "jac_norm_mean")
    pf, pr = mean_of(F, "jac_norm_p95"), mean_of(R, "jac_norm_p95")
    bullets.append(
        f"- **Lower Explosion Rate for ReFPO: {'holds' if lower + both_zero == n else verdict(lower, n)}** (lower in "
        f"{lower} of {n}, both zero in {both_zero}; ReFPO's is zero in {refpo_zero} of {n}). The Jacobian explosion "
        f"rate is lower for ReFPO in {jac_lower} of {n} and {compare(jr, jf)} on average ({jr:.3f} against {jf:.3f}); "
        f"the mean spectral norm is {compare(nr, nf)} for ReFPO ({nr:.2f} against {nf:.2f}), its 95th percentile "
        f"{compare(pr, pf)} ({pr:.2f} against {pf:.2f})."
    )
    # 3. FPO's 1-step below its 10-step
    below = [p for p in pairs if F[p]["return_1"] < F[p]["return_multi"]]
    others = [p for p in pairs if p not in below]
    bullets.append(
        f"- **FPO's 1-step return below its 10-step: {verdict(len(below), n)}**"
        + (
            " (not in "
            + ", ".join(
                f"{short(t)} seed {s}: N = 10 / N = 1 {F[(t, s)]['return_multi']:.0f} / {F[(t, s)]['return_1']:.0f}"
                for t, s in others
            )
            + ")."
            if others
            else "."
        )
    )
    # 4. ReFPO's 1-step near its 10-step, per task
    per_task = []
    for t in tasks:
        mine = [p for p in pairs if p[0] == t]
        near = sum(R[p]["return_1"] >= ONE_STEP_NEAR * R[p]["return_multi"] for p in mine)
        ones = [R[p]["return_1"] for p in mine]
        multis = [R[p]["return_multi"] for p in mine]
        word = "holds" if near == len(mine) else ("fails" if near == 0 else f"holds in {near} of {len(mine)} seeds")
        per_task.append(
            f"{word} on {short(t)}"
            + (f" in all {len(mine)} seeds" if near == 0 else "")
            + f" (N = 1 {min(ones):.0f}-{max(ones):.0f}, mean {_mean(ones):.0f}; N = 10 {min(multis):.0f}-"
            f"{max(multis):.0f}, mean {_mean(multis):.0f})"
        )
    text = (
        "- **ReFPO's 1-step return ≈ its 10-step one** (per run: the 1-step return at least "
        f"{ONE_STEP_NEAR:g} × the 10-step one): "
        + "; ".join(per_task)
        + ". Figure 3 shows both returns over env steps."
    )
    point = [t for t in tasks if t.endswith("point_mass")]
    if point:
        t = point[0]
        f1 = {s: fpo[t][s]["return_1"] for s in fpo[t]}
        r1 = _mean(refpo[t][s]["return_1"] for s in refpo[t])
        best = max(f1, key=f1.__getitem__)
        text += (
            f" FPO's 1-step return on {short(t)} is {compare(_mean(f1.values()), r1).replace('level', 'level with')}"
            f"{' than ReFPO' if _mean(f1.values()) != r1 else ' ReFPO'}'s ({_mean(f1.values()):.0f} on average "
            f"against {r1:.0f}; {f1[best]:.0f} in seed {best})."
        )
    text += " Why, and what coupled Reflow pairs and an adaptive λ do about it: [`one_step/`](one_step/README.md)."
    bullets.append(text)
    # 5. ReFPO above FPO at N = 10
    above_tasks = [
        t
        for t in tasks
        if mean_of(R, "return_multi", [p for p in pairs if p[0] == t])
        > mean_of(F, "return_multi", [p for p in pairs if p[0] == t])
    ]
    above_pairs = sum(R[p]["return_multi"] > F[p]["return_multi"] for p in pairs)
    smaller = [
        t
        for t in tasks
        if statistics.pstdev(refpo[t][s]["return_multi"] for s in refpo[t])
        < statistics.pstdev(fpo[t][s]["return_multi"] for s in fpo[t])
    ]
    means = ", ".join(
        f"{mean_of(R, 'return_multi', [p for p in pairs if p[0] == t]):.0f} against "
        f"{mean_of(F, 'return_multi', [p for p in pairs if p[0] == t]):.0f}"
        for t in tasks
    )
    on_average = verdict(len(above_tasks), len(tasks)).replace("holds in", "holds on average on")
    bullets.append(
        f"- **ReFPO above FPO at 10 steps: {on_average} tasks** ({means}), in {above_pairs} of {n} pairs; "
        f"ReFPO's spread over seeds (population std) is smaller on {count_text(len(smaller), len(tasks))} tasks."
    )
    # 6. ReFPO above PPO
    if ppo and all(ppo.get(t) for t in tasks):
        best_ppo = [
            t
            for t in tasks
            if _mean(r["return_multi"] for r in ppo[t].values())
            > max(_mean(r["return_multi"] for r in m[t].values()) for m in (fpo, refpo))
        ]
        pp, pr_ = _pooled(ppo, "return_multi").point, _pooled(refpo, "return_multi").point
        holds = pr_ > pp
        bullets.append(
            f"- **ReFPO above Gaussian PPO (the paper's average): {'holds' if holds else 'does not hold here'}**: PPO "
            f"has the best 10-step return on {count_text(len(best_ppo), len(tasks))} tasks at this budget "
            f"({pp:.0f} against ReFPO's {pr_:.0f} pooled)."
        )
    counted = f"counted over the {n} (task, seed) pairs with both an FPO and a ReFPO run"
    return appendix, counted, "\n".join(bullets)


# ------------------------------------------------------------------------------------------------ the page
def values() -> dict[str, object]:
    from refpo_warp.studies.grid.launch import STOP_GRACE_S
    from refpo_warp.studies.ray.backend import SYSTEM_RETRIES

    table, paper = sweeps()
    data = cpu_runs()
    cpu, note = cpu_table(data)
    appendix, counted, bullets = directions(data)
    tasks = sorted({t for by_task in data.values() for t in by_task})
    from results_reading import profile_steps

    by_steps: dict[int, list[str]] = {}
    for t in tasks:
        by_steps.setdefault(profile_steps(t), []).append(short(t))
    return {
        "sweeps_table": table,
        "paper_runs": paper["runs"],
        "paper_steps": paper["steps"],
        "ray_retries": SYSTEM_RETRIES,
        "stop_grace": f"{STOP_GRACE_S:g}",
        "cuda_iteration_steps": cuda_iteration_steps(),
        "cpu_steps": " or ".join(f"{steps_text(s)} ({', '.join(ts)})" for s, ts in sorted(by_steps.items())),
        "cpu_seeds": seeds_text(s for by_task in data.values() for runs in by_task.values() for s in runs),
        "cpu_table": cpu,
        "cpu_table_note": note,
        "appendix_c": appendix,
        "directions_count": counted,
        "directions": bullets,
    }


def main() -> None:
    args = main_args(__doc__.split("\n\n")[0]).parse_args()
    same = write_page(TEMPLATE, values(), check=args.check)
    if args.check and not same:
        sys.exit(1)
    print(f"{TEMPLATE.with_name('README.md')}: {'unchanged' if same else 'written'}")


if __name__ == "__main__":
    main()
