"""docs/results/finetuning/README.md, written whole from README.template.md and the study's committed files
(gridworld.sh, dmc.sh; nothing on the page is typed by hand).

    python docs/results/finetuning/tables.py [--check]                          # the page from the committed files
    python docs/results/finetuning/tables.py --keep [--runs runs/finetuning/gridworld]
    python docs/results/finetuning/tables.py --dmc

Reads: gridworld/ (each GridWorld stage's config.yaml, eval.json, progress.jsonl and the dataset's metadata.json);
dmc/, normalizers_updated/ and scratch/ (the DMC demonstrators, datasets, clones and every fine-tuning and
from-scratch run: the normalisers held, updated from the rollouts, from scratch); ../cpu_dmc/per_task.csv (PPO's final
return at the full CPU profile); ../learning_checks/records/gridworld_finetune_refpo.jsonl and
tests/learning/checks.py (the learning check's records and its collection and cloning options).

``--keep`` first copies the GridWorld runs' small files from ``--runs`` into gridworld/ and, where the Gaussian
clone's checkpoint is there, rolls the clone out again and keeps where its time-outs end
(gridworld/clone_gauss/timeout_rows.json). ``--dmc`` first copies the DMC runs' small files (runs/finetuning/dmc and
the sweeps of DMC_SOURCES under runs/sweeps) into dmc/, normalizers_updated/ and scratch/, and draws dmc_curves.png
(fine-tuned and from-scratch evaluation curves side by side) and dmc_remedies.png (ReFPO's fine-tuning beside each
remedy tried against its collapse). ``--check`` writes nothing: it compares the page with what the files say.

Intervals: the mean over seeds with rliable's 95 % stratified bootstrap interval, and rliable's probability of
improvement (refpo_warp/studies/reports/intervals.py).

The parts live beside this script: study_layout.py (paths, methods, thresholds), number_text.py (number formats and
intervals), gridworld_runs.py (--keep), gridworld_values.py (the GridWorld part), dmc_runs.py (the DMC runs as read),
dmc_comparisons.py and dmc_remedies.py (the DMC part) and dmc_figures.py (--dmc's figures).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

from dmc_comparisons import (
    demonstrator_facts,
    demonstrator_table,
    dmc_table,
    one_step_sentence,
    ppo_values,
    reach_sentence,
    scratch_values,
)
from dmc_figures import dmc_curves
from dmc_remedies import adaptive_values, collapse_values, held_values
from dmc_runs import Run, cpu_dmc_rows, group, keep_dmc
from gridworld_runs import keep
from gridworld_values import gridworld_values, learning_check_values
from number_text import span, thousands
from study_layout import (
    DMC_FIGURE,
    DMC_KEPT,
    DMC_METHODS,
    DMC_TASKS,
    REMEDIES_FIGURE,
    SCRATCH_KEPT,
    TEMPLATE,
    UPDATED_KEPT,
    read_json,
    read_yaml,
)

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.phrases import and_list

PAIRS = [(task, label) for task in DMC_TASKS for label, _, _ in DMC_METHODS]


def dmc_values() -> dict:
    facts = {task: demonstrator_facts(task) for task in DMC_TASKS}
    first = facts[DMC_TASKS[0]]
    fine = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(DMC_KEPT, task, label)]
    updated = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(UPDATED_KEPT, task, label)]
    scratch = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(SCRATCH_KEPT, task, label)]
    steps = {read_json(r.path / "eval.json")["env_steps"] for r in fine + updated + scratch}
    (ft_steps,) = steps
    evaluations = {result["episodes"] for r in fine for result in read_json(r.path / "eval.json")["results"].values()}
    periodic = Counter(b - a for r in fine for a, b in zip(r.curve[0], r.curve[0][1:]))
    interval_steps = periodic.most_common(1)[0][0]
    seeds_counts = sorted({len(group(k, t, m)) for k in (DMC_KEPT, SCRATCH_KEPT) for t, m in PAIRS} - {0})
    ratio_words, below = [], []
    for task, f in facts.items():
        r = f["data"] / f["ppo_final"]
        ratio_words.append(f"{r:.2f} on {task[4:]}")
        below += [task[4:]] if r < 0.5 else []
    weaker = all(f["data"] < f["ppo_final"] for f in facts.values())
    data_ratios = (
        f"The data's return over PPO's full-profile final is {and_list(ratio_words)}: "
        + ("below PPO's final on every task" if weaker else "not below PPO's final on every task")
        + (
            f", below the half the study aimed for on {and_list(below)} only."
            if below and len(below) < len(facts)
            else f", below the half the study aimed for on {'every task' if below else 'no task'}."
        )
    )
    gap = [
        f"{task[4:]}'s checkpoint evaluated at {f['used'][1]:.0f} ({f['periodic_episodes']} episodes) and its "
        f"{f['episodes']} collected episodes average {f['data']:.0f}"
        for task, f in facts.items()
    ]
    rule_differs = [task for task, f in facts.items() if f["rule"][0] != f["used"][0]]
    if rule_differs:
        rule = (
            "; ".join(
                f"On {t[4:]} the data come from iteration {facts[t]['used'][0]} ({facts[t]['used'][1]:.0f}), not from "
                f"iteration {facts[t]['rule'][0]} ({facts[t]['rule'][1]:.0f})"
                for t in rule_differs
            )
            + ", the checkpoint `half_return_checkpoint.py` picks from the committed progress rows (the evaluated "
            "checkpoint nearest the target up to the first evaluation that reaches it)."
        )
    else:
        rule = "Each task's data come from the checkpoint `half_return_checkpoint.py` picks from the committed rows."

    def minutes(runs: list[Run]) -> str:
        return span([r.train_time_s / 60 for r in runs], 1)

    return {
        "demonstrator_table": demonstrator_table(facts),
        "dmc_episodes": seeds_text({f["episodes"] for f in facts.values()}),
        "dmc_noise": and_list(sorted({f"{f['noise']:g}" for f in facts.values()})),
        "data_ratios": data_ratios,
        "data_gap": "; ".join(gap),
        "rule_sentence": rule,
        "ft_steps": thousands(ft_steps),
        "ft_share": f"{ft_steps / first['profile_steps']:.2f}",
        "profile_steps": thousands(first["profile_steps"]),
        "ft_minutes": minutes(fine),
        "updated_minutes": minutes(updated),
        "scratch_minutes": minutes(scratch),
        "final_episodes": seeds_text(evaluations),
        "seed_counts": " or ".join(str(n) for n in seeds_counts),
        "periodic_steps": thousands(interval_steps),
        "periodic_episodes": seeds_text({read_yaml(r.path / "config.yaml")["eval"]["interval_num_envs"] for r in fine}),
        "ppo_full": " / ".join(f"{f['ppo_final']:.0f}" for f in facts.values()),
        "ppo_full_runs": and_list(sorted({cpu_dmc_rows()[(t, "ppo")]["return_multi_n"] for t in DMC_TASKS})),
        "dmc_table": dmc_table(),
        "reach_sentence": reach_sentence(),
        "one_step_sentence": one_step_sentence(),
        "pm_seeds_held": seeds_text(r.seed for r in group(DMC_KEPT, "dmc_point_mass", "refpo")),
        **scratch_values(),
        **ppo_values(),
        **collapse_values(),
        **held_values(),
        **adaptive_values(),
    }


# ------------------------------------------------------------------------------------------------ the page
def page_values() -> dict:
    return {**gridworld_values(), **learning_check_values(), **dmc_values()}


def main() -> None:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args(__doc__)
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--runs", type=Path, default=Path("runs/finetuning/gridworld"), help="the GridWorld runs")
    parser.add_argument("--keep", action="store_true", help="copy the GridWorld runs' small files here first")
    parser.add_argument("--dmc", action="store_true", help="copy the DMC runs' small files here first; the figures")
    args = parser.parse_args()
    if args.check and (args.keep or args.dmc):
        parser.error("--check reads the committed files only: give it alone")
    if args.keep:
        keep(args.runs)
    if args.dmc:
        keep_dmc(Path("runs/finetuning/dmc"), Path("runs/sweeps"))
        print(dmc_curves(DMC_FIGURE), dmc_curves(REMEDIES_FIGURE, remedies=True))
    same = write_page(TEMPLATE, page_values(), check=args.check)
    if args.check and not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
