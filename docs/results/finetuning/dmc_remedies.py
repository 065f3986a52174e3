"""The page's account of ReFPO's collapse when fine-tuning with the normalisers updated, and of the remedies tried
(normalisers held, the critic's warm-up, adaptive λ and its schedule)."""

from __future__ import annotations

from dmc_comparisons import chosen_and_fresh, verdict
from dmc_runs import Run, final_returns, group, n10
from number_text import interval_cell, slashed, span
from study_layout import (
    DMC_KEPT,
    DMC_METHODS,
    DMC_TASKS,
    FALL,
    FLOWS_HELD,
    NAMES,
    ROOT,
    SCRATCH_KEPT,
    UPDATED_KEPT,
    prose,
    read_yaml,
)

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.intervals import Estimate, improvement_of
from refpo_warp.studies.reports.phrases import and_list


def collapse_values() -> dict:
    """The runs on point_mass with the normalisers updated (and plain ReFPO's with them held): each seed's returns
    and, at the last update, the signs that went with the fall."""
    task = "dmc_point_mass"
    lines = [
        (
            "| normalisers | run | N = 10: peak (iteration) → end, per seed | N = 1 at the end | spread at the end | "
            "one-step ratio at the end | clipped fraction at the end | Reflow loss at the end |"
        ),
        "|---|---|---|---|---|---|---|---|",
    ]
    rows = [(UPDATED_KEPT, "updated", label) for label, _, _ in DMC_METHODS] + [
        (DMC_KEPT, "held", label) for label in FLOWS_HELD
    ]
    warmup: dict[int, list[Run]] = {}
    for kept, how, label in rows:
        runs = group(kept, task, label)
        if not runs:
            continue
        flow = runs[0].n1 is not None
        w = read_yaml(runs[0].path / "config.yaml")["critic_warmup_iterations"]
        if flow:
            for r in runs:
                warmup.setdefault(w - 1, []).append(r)

        def per(key: str, digits: int, runs=runs, flow=flow) -> str:
            return slashed([r.at(key) for r in runs], digits) if flow else "-"

        peaks = " / ".join(f"{r.peak[0]:.0f} ({r.peak[1]}) → {r.n10:.0f}" for r in runs)
        lines.append(
            f"| {how} | {NAMES[label]} (seeds {seeds_text(r.seed for r in runs)}) | {peaks} | "
            f"{slashed([r.n1 for r in runs]) if flow else '-'} | {per('Flow/policy_spread', 4)} | "
            f"{per('Flow/one_step_ratio', 1)} | {per('Flow/clip_fraction', 2)} | {per('Loss/reflow', 2)} |"
        )
    ((last_warmup, flows),) = warmup.items()
    updated = group(UPDATED_KEPT, task, "refpo")
    held = group(DMC_KEPT, task, "refpo")
    onestep, ppo = group(UPDATED_KEPT, task, "refpo_onestep"), group(UPDATED_KEPT, task, "ppo")
    clone = final_returns(DMC_KEPT / task / "clone_refpo" / "eval.json")[0]

    def fell_text(runs) -> str:
        return f"{sum(r.fell for r in runs)} of {len(runs)}"

    fell_held = [r for r in held if r.fell]
    remedies = [
        f"{prose(label)}: {fell_text(group(UPDATED_KEPT, task, label))}"
        for label, base, _ in DMC_METHODS
        if label != base and group(UPDATED_KEPT, task, label)
    ]
    return {
        "collapse_table": "\n".join(lines),
        "fall_share": f"{FALL:g}",
        "clone_return": f"{clone:.0f}",
        "updated_peaks": slashed([r.peak[0] for r in updated]),
        "updated_peak_iterations": " / ".join(str(r.peak[1]) for r in updated),
        "updated_ends": slashed(n10(updated)),
        "updated_n1": slashed([r.n1 for r in updated]),
        "updated_fell": fell_text(updated),
        "onestep_fell": fell_text(onestep),
        "ppo_fell": fell_text(ppo),
        "ppo_updated": slashed(n10(ppo)),
        "warmup_iteration": last_warmup,
        "warmup_spread": span([r.at("Flow/policy_spread", last_warmup) for r in flows], 3),
        "warmup_ratio": span([r.at("Flow/one_step_ratio", last_warmup) for r in flows], 2),
        "warmup_runs": len(flows),
        "remedies_fell": "; ".join(remedies),
        "held_fall_sentence": (
            f"With the normalisers held, plain ReFPO on point_mass still fell in {fell_text(held)} seeds ("
            + and_list(
                [
                    f"seed {r.seed}: {r.peak[0]:.0f} at iteration {r.peak[1]}, {r.last_periodic:.0f} at the last "
                    "periodic evaluation"
                    for r in fell_held
                ]
            )
            + "): holding the normalisers does not stop the fall in every seed."
            if fell_held
            else f"With the normalisers held, none of plain ReFPO's {len(held)} seeds on point_mass fell."
        ),
    }


def held_values() -> dict:
    """The normalisers held against updated, on the seeds both ran."""
    lines = [
        "| task | method | held: mean [95 % CI] (seeds) | updated | P(held > updated) [95 % CI] | |",
        "|---|---|---|---|---|---|",
    ]
    verdicts = {}
    for task in DMC_TASKS:
        for label in ("refpo", "refpo_onestep", "ppo"):
            updated = group(UPDATED_KEPT, task, label)
            seeds = {r.seed for r in updated}
            held = [r for r in group(DMC_KEPT, task, label) if r.seed in seeds]
            p = improvement_of(n10(held), n10(updated))
            lines.append(
                f"| {task} | {NAMES[label]} | {interval_cell(n10(held))} | {interval_cell(n10(updated))} | "
                f"{p.text(2)} | {verdict(p, 'held', 'updated')} |"
            )
            verdicts[(task, label)] = p
    pm = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_point_mass" and p.side > 0]
    pm_not = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_point_mass" and p.side <= 0]
    re_sep = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_reacher_easy" and p.separates]
    sentence = (
        "On point_mass the interval puts the held normalisers above the updated ones for "
        f"{and_list(pm) if pm else 'no method'}"
        + (f", not for {and_list(pm_not)}" if pm_not else "")
        + "; on reacher_easy "
        + (f"it separates {and_list(re_sep)}." if re_sep else "it separates no method.")
    )
    return {"held_table": "\n".join(lines), "held_sentence": sentence}


def load_reflow_schedule():
    """refpo_warp/algorithms/reflow_schedule.py, loaded on its own: the package's __init__ would import torch."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("reflow_schedule", ROOT / "refpo_warp/algorithms/reflow_schedule.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def adaptive_values() -> dict:
    """Where adaptive λ sat (``Flow/reflow_coef`` in every adaptive run's progress rows), the fresh seeds' comparisons
    and the section's conclusion."""
    module = load_reflow_schedule()
    BAND, STEP, schedule = module.BAND, module.STEP, module.ReflowSchedule("adaptive")
    runs = [r for kept in (DMC_KEPT, UPDATED_KEPT) for task in DMC_TASKS for r in group(kept, task, "refpo_adaptive")]
    every = [
        r
        for kept in (DMC_KEPT, UPDATED_KEPT, SCRATCH_KEPT)
        for task in DMC_TASKS
        for label, base, _ in DMC_METHODS
        if base != "ppo"
        for r in group(kept, task, label)
    ]
    fixed_runs = [r for r in every if r not in runs]
    fixed = {row["Flow/reflow_coef"] for r in fixed_runs for row in r.rows}
    reached, stayed = [], 0
    for r in runs:
        lams = [row["Flow/reflow_coef"] for row in r.rows]
        first = next((i for i, v in enumerate(lams) if v >= schedule.high), None)
        if first is not None:
            reached.append(r.rows[first]["iteration"])
            stayed += all(v >= schedule.high for v in lams[first:])
    start_ratio = [r.at("Flow/one_step_ratio", 0) for r in runs]
    # the first row's λ is the schedule's first step from reflow_coef (taken before the first update)
    starts = {
        round(
            r.rows[0]["Flow/reflow_coef"] / STEP if ratio > schedule.target * BAND else r.rows[0]["Flow/reflow_coef"], 6
        )
        for r, ratio in zip(runs, start_ratio)
    }
    end_ratio = [r.at("Flow/one_step_ratio") for r in runs]
    sources = []
    for kept, how in ((DMC_KEPT, "held"), (UPDATED_KEPT, "updated")):
        for task in DMC_TASKS:
            n = len(group(kept, task, "refpo_adaptive"))
            if n:
                sources.append(f"{n} on {task[4:]} with the normalisers {how}")
    high = f"{schedule.high:g}"
    text = f"After a clone the ratio starts at {span(start_ratio, 2)}"
    if min(start_ratio) > schedule.target * BAND:
        text += f", above {schedule.target * BAND:g}, so λ rose from the first update on"
    text += (
        f"; it reached its upper bound {high} in {len(reached)} of {len(runs)} adaptive runs ({and_list(sources)})"
        + (f", at iteration {span(reached)}" if reached else "")
        + f", and stayed there to the last update in {stayed} of {len(runs)}; the ratio ended at "
        f"{span(end_ratio, 1)}."
    )
    if stayed == len(runs) and reached:
        text += f" In effect these runs are a fixed λ = {high} from iteration {span(reached)} on."
    if schedule.high not in fixed:
        text += (
            f" None of the fixed-λ runs on this page uses λ = {high} (they use "
            f"{and_list(sorted(f'{v:g}' for v in fixed))}), so these runs do not tell the schedule from the larger λ."
        )

    task = "dmc_point_mass"
    chosen, fresh = chosen_and_fresh(task)
    adaptive = n10(group(DMC_KEPT, task, "refpo_adaptive"), fresh)
    aspo = n10(group(DMC_KEPT, task, "refpo_aspo"), fresh)
    plain = n10(group(DMC_KEPT, task, "refpo"), fresh)
    ppo = n10(group(DMC_KEPT, task, "ppo"), fresh)
    p_plain = improvement_of(adaptive, plain)
    p_ppo = improvement_of(adaptive, ppo)
    p_aspo_ppo = improvement_of(aspo, ppo)
    reacher = n10(group(DMC_KEPT, "dmc_reacher_easy", "refpo_adaptive"))
    reacher_plain = n10(group(DMC_KEPT, "dmc_reacher_easy", "refpo"))
    p_reacher = improvement_of(reacher, reacher_plain)

    def separated(p: Estimate) -> str:
        return "the interval separates them" if p.separates else "the interval holds one half: not separated"

    def against(p: Estimate, name: str, other: str) -> str:
        if p.side > 0:
            return f"{name} ends above {other}"
        if p.side < 0:
            return f"{other} ends above {name}"
        return f"the seeds do not separate {name} from {other}"

    conclusion = (
        "So for fine-tuning ReFPO from a clone: hold the normalisers (the default). On point_mass's fresh seeds "
        f"{seeds_text(fresh)}, {against(p_plain, 'adaptive λ', 'plain ReFPO')}, {against(p_ppo, 'adaptive λ', 'PPO')} "
        f"and {against(p_aspo_ppo, 'ASPO', 'PPO')}; on reacher_easy {against(p_reacher, 'adaptive λ', 'plain ReFPO')}."
        " Adaptive λ stays an option (`algorithm.reflow_schedule=adaptive`; the paper's fixed λ stays the default)"
        + (f", and what it does here, a fixed λ = {high}, is untried on its own." if stayed == len(runs) else ".")
    )
    return {
        "lambda_step": f"{STEP:g}",
        "lambda_band": f"{schedule.target * BAND:g}",
        "lambda_band_low": f"{schedule.target / BAND:g}",
        "lambda_target": f"{schedule.target:g}",
        "lambda_high": high,
        "lambda_low": f"{schedule.low:g}",
        "lambda_start": (
            f"starting from {and_list(sorted(f'{v:g}' for v in starts))}"
            + (", the fixed λ of every other ReFPO run here" if starts == fixed else "")
        ),
        "lambda_sentence": text,
        "conclusion": conclusion,
        "fresh_seeds": seeds_text(fresh),
        "chosen_seeds": seeds_text(chosen),
        "fresh_adaptive": slashed(adaptive),
        "fresh_plain": slashed(plain),
        "fresh_aspo": slashed(aspo),
        "fresh_ppo": slashed(ppo),
        "fresh_vs_plain": f"P(adaptive > plain) = {p_plain.text(2)}, {separated(p_plain)}",
        "fresh_vs_ppo": f"P(adaptive > PPO) = {p_ppo.text(2)}, {separated(p_ppo)}",
        "reacher_adaptive": slashed(reacher),
        "reacher_plain": slashed(reacher_plain),
        "reacher_vs_plain": f"P(adaptive > plain) = {p_reacher.text(2)}, {separated(p_reacher)}",
    }
