#!/usr/bin/env python
"""FPO++ at its authors' locomotion defaults, at its small-task recipe and at the tuned CPU values: ``README.md`` in
this folder, written whole from ``README.template.md`` and the values this script computes (nothing typed in by hand):

    python docs/results/fpo_pp/make_page.py [--add-runs runs/sweeps/cpu_fpo_pp] [--check]

What it reads (every seed each file holds):

- ``report/runs.csv``: one row per ``refpo sweep cpu_fpo_pp`` run (``refpo report``'s per-run rows), every label of
  ``configs/sweep/cpu_fpo_pp.yaml`` that has run. ``--add-runs`` appends the rows of a sweep dir's report
  (``<dir>/report/runs.csv``) for (task, label, seed) not yet in the file, and copies each run's ``config.yaml``,
  ``eval.json``, periodic-evaluation rows and training statistics to ``runs/<task>/<label>/seed<k>/``: that is how
  the small-task recipe's (``fpo_pp_small``) and the gradient-clip ablation's rows arrive. A failed run counts as
  return 0.
- ``runs/<task>/<label>/seed<k>/config.yaml`` and ``eval.json``: each setting's values and run sizes.
- ``report_task_profile/runs.csv``: the first grid (FPO++'s loss on the task's ReFPO profile).
- ``../tuning/fresh/runs.csv`` (label ``fpo_pp``) and ``../tuning/fresh/runs/``: FPO++ at the tuned CPU values.
- ``../cpu_dmc/runs.csv``: PPO, FPO and ReFPO at the paper's values.
- ``configs/sweep/cpu_fpo_pp.yaml`` (labels, names, the authors' values it pins), ``configs/task/_dmc.yaml`` (the
  values the CPU profile sets for fpo_pp), ``fpo_pp_reference.yaml`` (FPO++'s locomotion run sizes, with their
  places in FPO++'s code), ``../tuning/criteria.yaml`` (the N = 1 share the project tests) and ``gpu_h200/``.

Intervals: rliable's stratified bootstrap (``refpo_warp/studies/reports/intervals.py``: ``aggregate``'s mean and
``improvement``).
"""

from __future__ import annotations

from pathlib import Path

from fpo_pp_runs import (
    AUTHORS,
    CLIP_LABELS,
    HERE,
    PROFILE_SUFFIX,
    REPORT,
    ROOT,
    RUNS,
    SETTINGS,
    SMALL,
    TASKS,
    TUNED_KEY,
    about,
    authors_sizes,
    authors_step_text,
    cell,
    finals,
    fmt_value,
    loco_size,
    methods,
    pct,
    reference,
    run_config,
    run_dirs,
    run_size,
    short,
    sweep_spec,
    values_table,
)
from fpo_pp_text import (
    all_table,
    clip_text,
    findings,
    gpu_values,
    lr_text,
    poi_rows,
    poi_table,
    run_times,
    settings_table,
    small_verdicts,
    sweep_text,
    what_ran,
)
from grad_norms import grad_norm_text, small_recipe_text

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs
from refpo_warp.studies.reports.results_page import page_main


# ------------------------------------------------------------------------------------------------ adding runs
def add_runs(sweep_dir: Path) -> None:
    """Append the sweep's new (task, label, seed) rows to report/runs.csv, copying their small files under runs/."""
    added = append_runs(sweep_dir, REPORT, RUNS, ROOT)
    print(f"{REPORT.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")


# ------------------------------------------------------------------------------------------------ the page
def values() -> dict[str, object]:
    ms = methods()
    data = {key: {s: finals(m, s) for s in SETTINGS} for key, m in ms.items()}
    small_present = any(data[SMALL]["multi"].values())
    v: dict[str, object] = {}

    # Sizes: ours at the authors' values against FPO++'s locomotion runs.
    loco, ref = loco_size(), reference()
    ours = authors_sizes()
    v["loco_robot"] = ref["robot"]
    v["loco_envs"] = f"{loco.envs:,}"
    v["loco_steps"] = str(loco.steps)
    v["loco_iterations"] = f"{loco.iterations:,}"
    v["loco_epochs"] = str(loco.epochs)
    v["loco_minibatches"] = str(loco.minibatches)
    v["loco_updates"] = f"{loco.updates:,}"
    v["loco_minibatch"] = f"{loco.minibatch:,}"
    v["our_sizes"] = "; ".join(
        f"{short(t)} {s.iterations} iterations × {s.epochs} epochs × {s.minibatches} minibatches = {s.updates:,} "
        f"({pct(s.updates / loco.updates)}) in minibatches of {s.envs} × {s.steps} / {s.minibatches} = "
        f"{s.minibatch:,} transitions ({pct(s.minibatch / loco.minibatch)})"
        for t, s in ours.items()
    )
    v["step_about"] = authors_step_text()
    v["mb_about"] = about([s.minibatch / loco.minibatch for s in ours.values()])
    iters = sorted({s.iterations for s in ours.values()})
    v["our_iterations"] = "-".join(str(i) for i in (iters[0], iters[-1])) if len(iters) > 1 else str(iters[0])
    envs = sorted({s.envs for s in ours.values()})
    v["our_envs"] = "-".join(str(e) for e in (envs[0], envs[-1])) if len(envs) > 1 else str(envs[0])
    from refpo_warp.algorithms.on_policy import OnPolicyAlgorithm
    from refpo_warp.utils.options import option_fields

    v["ema_warmup"] = str(ref["ema_warmup"])
    v["ema_ours"] = (
        "and so does ours (`ema_warmup`, `refpo_warp/algorithms/on_policy.py`)"
        if option_fields(OnPolicyAlgorithm)["ema_warmup"].default == ref["ema_warmup"]
        else "ours starts at another count (`ema_warmup`, `refpo_warp/algorithms/on_policy.py`)"
    )
    v["ema_live"] = (
        "so every run here is evaluated on its live weights, as FPO++'s would be at this length"
        if max(s.iterations for s in ours.values()) < ref["ema_warmup"]
        else "so the longer runs here are evaluated on their average"
    )

    v["profile_suffix"] = PROFILE_SUFFIX
    v.update(sweep_text(ms))
    v["authors_name"] = ms[AUTHORS].name
    table, missing = values_table(ms)
    v["values_table"] = table
    v["values_missing"] = "Columns without a committed run show `--`: " + ", ".join(missing) + "." if missing else ""
    v["settings_table"] = settings_table(ms, data)

    # The small recipe against the other two settings, and the tuned values against the authors'.
    if small_present:
        pairs = [
            (SMALL, AUTHORS, ("the small-task recipe", "the locomotion defaults")),
            (SMALL, TUNED_KEY, ("the small-task recipe", "the tuned values")),
            (TUNED_KEY, AUTHORS, ("the tuned values", "the locomotion defaults")),
        ]
    else:
        pairs = [(TUNED_KEY, AUTHORS, ("the tuned values", "the locomotion defaults"))]
    rows, kept = poi_rows(pairs, ms, data)
    v["small_poi_table"] = poi_table(rows)
    v["small_verdicts"] = (
        small_verdicts(kept, ms)
        if small_present
        else "- **The small-task recipe**: no committed run yet (`report/runs.csv` has no `fpo_pp_small` row); its "
        "rows, and its probabilities of improvement over the locomotion defaults and over the tuned values, appear "
        "here when they do."
    )
    tuned_groups: dict[int, list[str]] = {1: [], -1: [], 0: []}
    for x, y, task, s, p in kept:
        if x == TUNED_KEY and y == AUTHORS and s == "multi":
            tuned_groups[p.side].append("over the three tasks" if task is None else f"on {short(task)}")
    bits = []
    if tuned_groups[1]:
        bits.append("its runs beat the locomotion defaults' " + ", ".join(tuned_groups[1]))
    if tuned_groups[-1]:
        bits.append("the locomotion defaults' beat them " + ", ".join(tuned_groups[-1]))
    if tuned_groups[0]:
        bits.append("the seeds do not separate them " + ", ".join(tuned_groups[0]))
    v["tuned_verdict"] = "; ".join(bits)

    # The other comparisons.
    other = [
        (key, AUTHORS, (ms[key].name, "the locomotion defaults"))
        for key, m in ms.items()
        if m.csv == REPORT and key not in (AUTHORS, SMALL, *CLIP_LABELS)
    ]
    if "profile:fpo_pp" in data:
        other.append(("profile:fpo_pp", AUTHORS, ("the first grid's FPO++", "the locomotion defaults")))
    for label in ("profile:fpo_pp_mean_ratio", "profile:fpo_pp_ppo_clip"):
        if label in data:
            other.append(
                (label, "profile:fpo_pp", (ms[label].name.split(", " + PROFILE_SUFFIX)[0], "the first grid's FPO++"))
            )
    rows, kept_other = poi_rows(other, ms, data)
    v["other_poi_table"] = poi_table(rows)
    reflow = [p for x, _, _, _, p in kept_other if x == "refpo_pp"]
    v["reflow_separate"] = (
        "no task and no setting in which the seeds separate them"
        if reflow and not any(p.separates for p in reflow)
        else f"the seeds separate them in {sum(p.separates for p in reflow)} of {len(reflow)} cases"
    )
    spec = {m["label"]: m for m in sweep_spec()["methods"]}
    authors = spec[AUTHORS].get("overrides") or {}
    v["clip_setup"] = "; ".join(
        f"`{label}` sets "
        + ", ".join(
            f"`{k}: {fmt_value(x)}`" for k, x in (spec[label].get("overrides") or {}).items() if k not in authors
        )
        for label in CLIP_LABELS
        if label in spec
    )
    v["joint_clip"] = ", ".join(
        f"`{k}: {fmt_value(x)}`"
        for k, x in (run_config(ms[AUTHORS], TASKS[1]) or {}).items()
        if k in ("algorithm.max_grad_norm", "algorithm.joint_grad_clip")
    )
    ran_ablation = [k for k in ("fpo_pp_mean_ratio", "fpo_pp_ppo_clip") if k in data and any(data[k]["multi"].values())]
    v["ablation_authors_state"] = (
        "have run: rows " + ", ".join(f"`{k}`" for k in ran_ablation) + " in the tables above"
        if ran_ablation
        else "have not run: `report/runs.csv` has no `fpo_pp_mean_ratio` or `fpo_pp_ppo_clip` row"
    )
    every = {run_size(r).iterations for r in RUNS.glob("*/*/seed*") if (r / "eval.json").exists()}
    v["all_iterations"] = f"{min(every)}-{max(every)}" if len(every) > 1 else str(min(every))
    proto = load_yaml(run_dirs(RUNS, TASKS[0], AUTHORS)[0] / "config.yaml")["eval"]
    v["eval_protocol"] = (
        ", ".join(f"N = {n}" for n in proto["flow_steps"])
        + ", each from "
        + " and from ".join(f"{x} initial noise" for x in proto["initial_noise"])
    )
    v["all_table"] = all_table(ms, data)

    v.update(findings(ms, data))
    v["lr_text"] = lr_text(data, ms)
    v["clip_text"] = clip_text(data, ms)
    max_norm = (run_config(ms[AUTHORS], TASKS[1]) or {}).get("algorithm.max_grad_norm", 1.0)
    v["small_recipe_text"] = small_recipe_text({short(t): run_dirs(RUNS, t, SMALL) for t in TASKS})
    v["grad_norm_text"] = grad_norm_text(
        {label: run_dirs(RUNS, TASKS[1], label) for label in CLIP_LABELS}, run_dirs(RUNS, TASKS[1], AUTHORS), max_norm
    )
    ran, missing_labels = what_ran()
    v["what_ran"] = ran
    v["not_run"] = missing_labels
    v["run_times"] = run_times()
    # The first grid: its ablation against its own FPO++, seed by seed.
    prof = []
    pm = "dmc_point_mass"
    base = data.get("profile:fpo_pp")
    for label in ("profile:fpo_pp_mean_ratio", "profile:fpo_pp_ppo_clip"):
        if label not in data or base is None:
            continue
        seeds = sorted(set(data[label]["multi"][pm]) & set(base["multi"][pm]))
        higher = sum(data[label]["multi"][pm][s] > base["multi"][pm][s] for s in seeds)
        name = ms[label].name.split(", " + PROFILE_SUFFIX)[0]
        prof.append(f"{name}: {cell(data[label]['multi'][pm])}, higher in {higher} of {len(seeds)} seeds")
    v["profile_ablation"] = "; ".join(prof)
    v["profile_fpo_pm"] = cell(base["multi"][pm]) if base else "--"
    v["profile_vs_authors"] = (
        "; ".join(f"{short(t)} {cell(base['multi'][t])} against {cell(data[AUTHORS]['multi'][t])}" for t in TASKS)
        if base
        else "--"
    )
    v.update(gpu_values())
    return v


def main() -> None:
    page_main(__doc__.splitlines()[0], HERE / "README.template.md", values, add_runs)


if __name__ == "__main__":
    main()
