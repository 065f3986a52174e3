#!/usr/bin/env python
"""``README.md`` in this folder, written whole from ``README.template.md`` and the values this script computes from
the committed data files (nothing typed in by hand):

    python docs/results/tuning/make_page.py [--check] [--sync runs/tune/cpu_dmc] [--sync-fresh DIR] [--sync-budget DIR]

``--sync`` first copies a study's small files here (``study/``: the Optuna journal, trials.csv, chosen.yaml,
evaluate.yaml, and each trial run's config.yaml, eval.json and periodic-evaluation rows); ``--sync-fresh`` the
fresh-seed sweep's report (``fresh/runs.csv``, from ``refpo report``) and its runs' small files; ``--sync-budget``
the budget sweep's runs' small files (``budget/``). Then it writes README.md
(``refpo_warp/studies/reports/results_page.py``) and ``budget_curves.png``; ``--check`` only compares the page with
what the data says (exit 1 if it differs).

What it reads: ``configs/tune/cpu_dmc.yaml`` (the search), ``study/`` (trials, chosen values, journal times, trial run
configs), ``fresh/runs.csv`` and ``fresh/runs/`` (the chosen values on fresh seeds: every seed the file holds), the
committed rows at the paper's values (``COMMITTED``: every seed those files hold), ``budget.yaml`` and ``budget/``
(the budget curves), ``configs/task/_dmc.yaml`` (the paper's and the CPU profile's budgets and passes) and
``criteria.yaml`` (the thresholds the verdicts test). Every sentence whose verdict depends on the data is written here
or in the modules beside it: ``study_files.py`` (paths, names, number formats), ``sync_runs.py`` (the --sync
options), ``study_tables.py`` (the study's trials and chosen values), ``fresh_seeds.py`` (the fresh-seed runs),
``budget_curves.py`` (the budget runs and their figure) and ``verdict_prose.py`` (the data-dependent sentences).
"""

from __future__ import annotations

import csv
import statistics
import sys
from pathlib import Path

from budget_curves import budget_runs, budget_runs_table, budget_scale, curves_table
from fresh_seeds import fresh_analysis, fresh_table, one_step_counts, own_name, read_runs
from study_files import (
    BUDGET,
    BUDGET_FILE,
    COMMITTED,
    CRITERIA,
    DMC_PROFILE,
    FRESH,
    LABELS,
    STUDY,
    TASKS,
    TEMPLATE,
    TUNING_FILE,
    fmt,
    number,
    read_yaml,
    share_text,
    short,
    steps_text,
    times_text,
)
from study_tables import (
    budget_table,
    chosen,
    chosen_one_step,
    chosen_table,
    own_values,
    profile_values,
    search_times,
    spaces_table,
    trials,
    trials_table,
)
from sync_runs import sync_budget, sync_fresh, sync_study
from verdict_prose import (
    adoption,
    against_paper,
    budget_prose,
    failures_text,
    goal_summary,
    goal_text,
    iqm_summary,
    means_text,
    range_text,
    runs_text,
    versus,
    vs_ppo_summary,
)

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.phrases import and_list


def page_values(check: bool) -> dict[str, object]:
    """Every field of README.template.md; with ``check`` budget_curves.png is left as it is."""
    from refpo_warp.runner.build import num_iterations

    crit, spec, dmc = read_yaml(CRITERIA), read_yaml(TUNING_FILE), read_yaml(DMC_PROFILE)
    fresh = fresh_analysis()
    profile_now = profile_values()
    above = crit["adopt"]["above"]
    rows = trials()
    v: dict[str, object] = {}

    # the CPU profile and the paper's budget
    trial_cfg = read_yaml(next(STUDY.glob("runs/*/trial*/*/config.yaml")))
    v["cpu_steps"] = steps_text(trial_cfg["total_env_steps"])
    v["cpu_iterations"] = num_iterations(trial_cfg)
    v["num_envs"] = trial_cfg["num_envs"]
    paper_steps = dmc["by_device"]["cuda"]["total_env_steps"]
    v["paper_steps"] = steps_text(paper_steps)
    v["paper_multiple"] = fmt(paper_steps / trial_cfg["total_env_steps"])
    v["paper_passes"] = dmc["_actor_critic"]["num_learning_epochs"]
    v["own_passes"] = fmt(number(own_values("refpo")["algorithm.num_learning_epochs"]))

    # the intro: the committed rows at the paper's values
    ppo_c, refpo_c = read_runs(*COMMITTED["ppo"][:2]), read_runs(*COMMITTED["refpo"][:2])
    ppo_mean = [statistics.mean(x[0] for x in ppo_c.returns[t].values()) for t in TASKS]
    refpo_mean = [statistics.mean(x[0] for x in refpo_c.returns[t].values()) for t in TASKS]
    v["intro_tasks"] = " / ".join(short(t) for t in TASKS)
    v["intro_ppo"] = " / ".join(f"{x:.0f}" for x in ppo_mean)
    v["intro_refpo"] = " / ".join(f"{x:.0f}" for x in refpo_mean)
    v["intro_ppo_above"] = f"{sum(a > b for a, b in zip(ppo_mean, refpo_mean))} of {len(TASKS)}"
    v["intro_seeds"] = seeds_text({s for t in TASKS for s in ppo_c.returns[t]})
    v["n_tasks"] = len(TASKS)
    left = [t for t in TASKS if t not in spec["tasks"]]
    v["untuned_tasks"] = and_list(
        f"{short(t)}, where PPO's committed mean is {m:.0f}" for t, m in zip(TASKS, ppo_mean) if t in left
    )

    # the search
    v["trials_budget"] = spec["trials"]
    v["search_spent"] = len(rows)
    v["search_minutes"] = f"{sum(float(r['seconds']) for r in rows if r.get('seconds')) / 60:.0f}"
    v["search_start"], v["search_end"] = search_times()
    v["tune_tasks"] = and_list(short(t) for t in spec["tasks"])
    v["tune_seed"] = spec["seed"]
    v["references"] = and_list(f"{spec['objective']['reference'][t]:g}" for t in spec["tasks"])
    v["sampler_startup"] = spec["sampler"]["startup_trials"]
    pruner = spec["pruner"]
    v["prune_percentile"] = fmt(pruner["percentile"])
    v["prune_from"] = pruner["warmup_evaluations"] + 1
    v["prune_startup"] = pruner["startup_trials"]
    complete = next(STUDY.glob("runs/*/trial*/*/progress_eval.jsonl"))
    v["tune_evaluations"] = sum(1 for line in complete.read_text().splitlines() if line.strip())
    v["eval_episodes"] = trial_cfg["eval"]["interval_num_envs"]
    lr = next(d for k, d in spec["methods"][0]["space"].items() if k == "algorithm.learning_rate")
    paper_lr = float(own_values("ppo")["algorithm.learning_rate"])
    v["lr_paper"] = fmt(paper_lr)
    v["lr_below"] = times_text(paper_lr / lr["low"])
    v["lr_above"] = times_text(lr["high"] / paper_lr)

    # the tables of the search
    v["spaces_table"] = spaces_table(profile_now)
    v["budget_table"] = budget_table()
    v["trials_table"] = trials_table()
    v["chosen_table"] = chosen_table()
    v["chosen_one_step"] = chosen_one_step(crit)

    # tuned ReFPO's values against the paper's
    picked, own_refpo = chosen(), own_values("refpo")
    v["refpo_lr_ratio"] = times_text(
        picked["refpo"]["overrides"]["algorithm.learning_rate"] / float(own_refpo["algorithm.learning_rate"])
    )
    v["refpo_lambda_ratio"] = times_text(
        picked["refpo"]["overrides"]["algorithm.reflow_coef"] / float(own_refpo["algorithm.reflow_coef"])
    )
    v["refpo_own_lambda"] = fmt(number(own_refpo["algorithm.reflow_coef"]))
    v["refpo_own_lr"] = fmt(number(own_refpo["algorithm.learning_rate"]))

    # the fresh seeds
    goal = crit["goal"]["one_step"]
    v["hold_share"] = f"{goal['share']:g}"
    v["within_share"] = share_text(crit["report"]["within"])
    v["goal_tasks"] = crit["goal"]["reach_tasks"]
    v["adopt_above"] = f"{above:g}"
    v["fresh_table"] = fresh_table(fresh, crit)
    fresh_csv = list(csv.DictReader((FRESH / "runs.csv").open(encoding="utf-8"))) if fresh else []
    v["fresh_runs"] = len(fresh_csv)
    v["fresh_failed_count"] = sum(r["status"] == "failed" for r in fresh_csv)
    v["fresh_seeds"] = seeds_text({int(r["seed"]) for r in fresh_csv})
    onestep_cfg = read_yaml(next(FRESH.glob("runs/*/refpo_onestep/seed*/config.yaml")))
    v["onestep_coef"] = fmt(onestep_cfg["algorithm"]["one_step_coef"])
    if fresh is not None:
        committed = []
        for label in LABELS:
            key = f"{label}/paper"
            if key in fresh.rows:
                committed.append(f"{COMMITTED[label][2]}, seeds {seeds_text(fresh.rows[key].seeds)}")
        v["committed_sources"] = "; ".join(dict.fromkeys(committed))
        v["ppo_norm_seeds"] = seeds_text(fresh.rows["ppo/paper"].seeds)
        v["summary_vs_ppo"] = vs_ppo_summary(fresh, above)
        v["summary_iqm"] = iqm_summary(fresh)
        v["summary_adopted"], v["adopt_text"] = adoption(fresh, crit, profile_now)
        row = fresh.rows[f"{goal['method']}/tuned"]
        held, near, total, misses = one_step_counts(row, goal["share"], crit["report"]["within"])
        v["onestep_iqm"] = fresh.iqm[row.key].text(2)
        v["onestep_held"] = f"{held} of {total}"
        v["onestep_within"] = f"{near} of {total}"
        v["goal_summary"] = goal_summary(fresh, crit)
        v["goal_text"] = goal_text(fresh, crit)
        v["failures_text"] = failures_text(fresh)

        refpo = fresh.rows["refpo/tuned"]
        failed = len(refpo.runs.failed)
        r_held, _, r_total, _ = one_step_counts(refpo, goal["share"], crit["report"]["within"])
        v["refpo_summary"] = (
            f"{failed} of its {len(refpo.seeds) * len(TASKS)} runs failed (counted as 0), and its N = 1 ≥ "
            f"{goal['share']:g} × N = 10 holds in {r_held} of {r_total} runs"
        )
        v["ppo_vs_paper"] = (
            f"{against_paper(fresh, 'ppo')}; IQM {fresh.iqm['ppo/tuned'].text(2)} against "
            f"{fresh.iqm['ppo/paper'].text(2)}; {versus(fresh.vs_own['ppo'], own_name('ppo'), above)}"
        )
        v["ppo_tuning_score"] = f"{picked['ppo']['score']:.3f}"
        v["refpo_vs_paper"] = (
            f"{against_paper(fresh, 'refpo')}; {versus(fresh.vs_own['refpo'], own_name('refpo'), above)}. Its runs, "
            "N = 10 (N = 1): " + "; ".join(f"{short(t)} {runs_text(refpo, t)}" for t in TASKS)
        )
        v["onestep_text"] = (
            f"means {means_text(row)}, IQM {fresh.iqm[row.key].text(2)}; N = 1 ≥ {goal['share']:g} × N = 10 in "
            f"{held} of {total} runs"
            + (f" (not in {'; '.join(misses)})" if misses else "")
            + f", |N = 1 − N = 10| ≤ {share_text(crit['report']['within'])} of N = 10 in {near} of {total}; tuned "
            f"ReFPO without the one-step term holds N = 1 ≥ {goal['share']:g} × N = 10 in {r_held} of {r_total}. "
            f"Against the paper-values `onestep_c03`: {versus(fresh.vs_own[row.label], own_name(row.label), above)}"
        )
        fpo = fresh.rows["fpo_pp/tuned"]
        v["fpo_text"] = (
            f"its chosen values take its means from {means_text(fresh.rows['fpo_pp/paper'])} to {means_text(fpo)} "
            f"({versus(fresh.vs_own['fpo_pp'], own_name('fpo_pp'), above)}); its tuned runs range "
            + ", ".join(f"{range_text(fpo, t)} on {short(t)}" for t in TASKS)
        )

    # the budget curves
    runs = budget_runs()
    if runs:
        profile, budget_steps, multiple = budget_scale()
        v["budget_multiple"] = multiple
        v["budget_steps"] = steps_text(budget_steps)
        task = short(read_yaml(BUDGET_FILE)["tasks"][0])
        v["curves_table"] = curves_table(runs, profile, multiple, plot=None if check else task)
        v["budget_runs_table"] = budget_runs_table(runs, profile, multiple, crit["report"]["fall"])
        v["fall_share"] = f"{crit['report']['fall']:g}"
        v["budget_eval_episodes"] = read_yaml(next(BUDGET.glob("*/*/seed*/config.yaml")))["eval"]["interval_num_envs"]
        v.update(budget_prose(runs, fresh, profile, multiple, crit))
    return v


def main() -> int:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args(__doc__.split("\n\n")[0])
    parser.add_argument("--sync", type=Path, help="a refpo tune out dir, e.g. runs/tune/cpu_dmc")
    parser.add_argument("--sync-fresh", type=Path, help="the fresh-seed sweep dir (with its report/)")
    parser.add_argument("--sync-budget", type=Path, help="the budget sweep dir")
    args = parser.parse_args()
    if args.check and (args.sync or args.sync_fresh or args.sync_budget):
        parser.error("--check compares the page with the committed data: it takes no --sync option")
    for folder, sync in ((args.sync, sync_study), (args.sync_fresh, sync_fresh), (args.sync_budget, sync_budget)):
        if folder is not None:
            sync(folder)
    same = write_page(TEMPLATE, page_values(args.check), check=args.check)
    page = TEMPLATE.with_name("README.md")
    if args.check:
        print(f"{page}: {'as the data says' if same else 'differs from what the data says'}")
        return 0 if same else 1
    print(f"{page}: {'unchanged' if same else 'written'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
