"""The page's DMC comparisons: the demonstrators, the fine-tuned runs against the data and PPO's full-profile return,
against the same method from scratch and against PPO from its Gaussian clone, and N = 1 against N = 10."""

from __future__ import annotations

import math
from pathlib import Path

from dmc_runs import Run, final_returns, first_reaching, group, load_run, n10, return_targets, run_groups
from half_return_checkpoint import nearest_up_to_crossing
from number_text import (
    interval_cell,
    ksteps,
    mean_estimate,
    seconds,
    slashed,
    span,
    thousands,
)
from study_layout import DMC_KEPT, DMC_TASKS, FLOWS_HELD, HERE, NAMES, SCRATCH_KEPT, prose, read_json, read_yaml

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.intervals import Estimate, improvement_of
from refpo_warp.studies.reports.phrases import and_list


# ------------------------------------------------------------------------------------------------ DMC: the page
def demonstrator_facts(task: str) -> dict:
    root = DMC_KEPT / task
    cfg = read_yaml(root / "demonstrator" / "config.yaml")
    evaluation = read_json(root / "demonstrator" / "eval.json")
    run = load_run(root / "demonstrator")
    meta = read_json(root / "data" / "metadata.json")
    policy = meta["refpo"]["policy"]
    data, ppo_final = return_targets(task)
    target = round(ppo_final / 2)  # dmc.sh's TARGET: half of PPO's full-profile final
    evaluated = [(r["iteration"], r["eval/return"]) for r in run.rows if "eval/return" in r]
    crossing = next(i for i, (_, v) in enumerate(evaluated) if v >= target)
    rule = nearest_up_to_crossing(evaluated, target)
    used = next(e for e in evaluated if e[0] == policy["iteration"])
    clones = {name: read_json(root / name / "eval.json") for name in ("clone_refpo", "clone_ppo")}
    per_iteration = cfg["num_envs"] * cfg["runner"]["num_steps_per_env"]
    return {
        "iterations": len(run.rows),
        "env_steps": evaluation["env_steps"],
        "train_time": evaluation["train_time_s"],
        "target": target,
        "ppo_final": ppo_final,
        "crossing": evaluated[crossing],
        "used": used,
        "rule": rule,
        "episodes": meta["total_episodes"],
        "data": data,
        "noise": policy["action_noise_std"],
        "sample": policy["sample"],
        "collect": meta["refpo"]["collect_time_s"],
        "clones": clones,
        "periodic_episodes": cfg["eval"]["interval_num_envs"],
        "profile_steps": math.ceil(read_yaml(root / "demonstrator" / "config.yaml")["total_env_steps"] / per_iteration)
        * per_iteration,
    }


def demonstrator_table(facts: dict) -> str:
    tasks = list(facts)
    lines = ["| | " + " | ".join(tasks) + " |", "|---" * (len(tasks) + 1) + "|"]

    def row(name: str, cell) -> None:
        lines.append(f"| {name} | " + " | ".join(cell(facts[t]) for t in tasks) + " |")

    row(
        "PPO demonstrator: iterations (env steps), training time",
        lambda f: f"{f['iterations']} ({thousands(f['env_steps'])}), {seconds(f['train_time'])}",
    )
    row("target: half of PPO's full-profile final (`cpu_dmc`)", lambda f: f"{f['target']} (of {f['ppo_final']:.0f})")
    row(
        "first periodic evaluation at or above the target: iteration (return)",
        lambda f: f"{f['crossing'][0]} ({f['crossing'][1]:.0f})",
    )
    row(
        "the checkpoint the data come from: iteration (its periodic evaluation)",
        lambda f: f"{f['used'][0]} ({f['used'][1]:.0f})",
    )
    row(
        "`half_return_checkpoint.py`'s rule on the committed rows picks",
        lambda f: f"{f['rule'][0]} ({f['rule'][1]:.0f})",
    )
    row("the data: episodes (collection time)", lambda f: f"{f['episodes']} ({seconds(f['collect'])})")
    row(
        "the data's return, over PPO's full-profile final",
        lambda f: f"{f['data']:.0f}, {f['data'] / f['ppo_final']:.2f}",
    )

    def clone(name: str):
        def cell(f: dict) -> str:
            p = f["clones"][name]["pretrain"]
            return f"{p['epochs_run']} epochs{' (stopped early)' if p['stopped_early'] else ''}, {seconds(p['time_s'])}"

        return cell

    row("flow clone: epochs, time", clone("clone_refpo"))
    row("Gaussian clone: epochs, time", clone("clone_ppo"))
    return "\n".join(lines)


def dmc_table() -> str:
    header = (
        "| task | method, from | return N = 10 (PPO: mean action), mean [95 % CI] (seeds) | N = 1 | "
        "env steps to the data's return | to PPO's full-profile final |"
    )
    lines = [header, "|---|---|---|---|---|---|"]
    for task in DMC_TASKS:
        root = DMC_KEPT / task
        meta = read_json(root / "data" / "metadata.json")["refpo"]
        data, ppo_final = return_targets(task)
        demo = Path(meta["policy"]["checkpoint"]).stem
        lines.append(
            f"| {task} | demonstrations: PPO's {demo}, mean action + noise {meta['policy']['action_noise_std']:g} "
            f"| {data:.0f} over the dataset's episodes | | | |"
        )
        for name, what in (("clone_refpo", "flow clone (0 env steps)"), ("clone_ppo", "Gaussian clone (0 env steps)")):
            multi, one = final_returns(root / name / "eval.json")
            lines.append(f"| {task} | {what} | {multi:.0f} | {'-' if one is None else f'{one:.0f}'} | | |")
        for start, _, _, what, dirs in run_groups(task):
            if "normalisers updated" in start:
                continue  # the collapse table's
            runs = [load_run(r) for r in dirs]
            ones = [r.n1 for r in runs if r.n1 is not None]
            reach = [ksteps_list([first_reaching(r.curve, target) for r in runs]) for target in (data, ppo_final)]
            lines.append(
                f"| {task} | {what}, from {start} | {interval_cell(n10(runs))} | "
                f"{interval_cell(ones) if ones else '-'} | {reach[0]} | {reach[1]} |"
            )
    return "\n".join(lines)


def ksteps_list(values: list[float | None]) -> str:
    return ", ".join(ksteps(v) for v in values)


def chosen_and_fresh(task: str) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The seeds the remedies were chosen on (remedies.yaml's) and the task's fresh seeds: those of its runs with the
    normalisers held that are not among them (empty where the task has no others)."""
    chosen = tuple(sorted(read_yaml(HERE / "remedies.yaml")["seeds"]))
    held = {r.seed for label in FLOWS_HELD + ("ppo",) for r in group(DMC_KEPT, task, label)}
    return chosen, tuple(sorted(held - set(chosen)))


def versus_scratch(task: str, label: str) -> tuple[tuple[Run, ...], tuple[Run, ...], Estimate]:
    fine, scratch = group(DMC_KEPT, task, label), group(SCRATCH_KEPT, task, label)
    return fine, scratch, improvement_of(n10(fine), n10(scratch))


def verdict(p: Estimate, better: str, worse: str) -> str:
    if p.side > 0:
        return f"{better} above"
    if p.side < 0:
        return f"{worse} above"
    return "not separated"


def scratch_values() -> dict:
    lines = [
        "| task | method | fine-tuned: mean [95 % CI] (seeds) | from scratch | P(fine-tuned > scratch) [95 % CI] | |",
        "|---|---|---|---|---|---|",
    ]
    separated, not_separated = [], []
    for task in DMC_TASKS:
        for label in ("refpo", "refpo_onestep", "ppo"):
            fine, scratch, p = versus_scratch(task, label)
            lines.append(
                f"| {task} | {NAMES[label]} | {mean_estimate(tuple(n10(fine))).text()} (seeds "
                f"{seeds_text(r.seed for r in fine)}) | {mean_estimate(tuple(n10(scratch))).text()} (seeds "
                f"{seeds_text(r.seed for r in scratch)}) | {p.text(2)} | {verdict(p, 'fine-tuned', 'scratch')} |"
            )
            name = f"{prose(label)} on {task[4:]}"
            if p.side > 0:
                separated.append(name)
            else:
                not_separated.append(
                    f"{name} (P = {p.point:.2f}; from scratch its seeds end at {slashed(n10(scratch))})"
                )
    sentence = (
        f"The interval puts fine-tuning above starting from scratch for {and_list(separated) if separated else 'none'}"
    )
    sentence += f"; it holds one half, separating nothing, for {and_list(not_separated)}." if not_separated else "."
    return {"scratch_table": "\n".join(lines), "scratch_sentence": sentence}


def reach_sentence() -> str:
    """Which runs reach the data's return and PPO's full-profile final, and when."""
    parts, full = [], []
    for task in DMC_TASKS:
        data, ppo_final = return_targets(task)
        fine = [r for label in ("refpo", "refpo_onestep", "ppo") for r in group(DMC_KEPT, task, label)]
        scratch = [r for label in ("refpo", "refpo_onestep", "ppo") for r in group(SCRATCH_KEPT, task, label)]
        at = [first_reaching(r.curve, data) for r in fine]
        hit = [s for s in at if s is not None]
        at_scratch = [s for s in (first_reaching(r.curve, data) for r in scratch) if s is not None]
        text = (
            f"on {task[4:]} {len(hit)} of {len(fine)} fine-tuned runs (ReFPO, `refpo_onestep`, PPO) reach the "
            f"data's return ({data:.0f})"
            + (f", within {span([s / 1000 for s in hit], 0, 'k-')}k env steps" if hit else "")
            + f", and {len(at_scratch)} of {len(scratch)} runs from scratch"
            + (f", at {span([s / 1000 for s in at_scratch], 0, 'k-')}k" if at_scratch else "")
        )
        parts.append(text)
        counts: dict[str, list[str]] = {}
        for label in FLOWS_HELD + ("ppo",):
            runs = group(DMC_KEPT, task, label)
            if runs:
                n = sum(first_reaching(r.curve, ppo_final) is not None for r in runs)
                counts.setdefault(f"{n} of {len(runs)}", []).append(prose(label))
        if len(counts) == 1:
            full.append(f"on {task[4:]} ({ppo_final:.0f}) {next(iter(counts))} seeds of each method")
        else:
            listed = "; ".join(f"{c} seeds of {and_list(m)}" for c, m in counts.items())
            full.append(f"on {task[4:]} ({ppo_final:.0f}) {listed}")
    return (
        "Reaching the data's return: " + "; ".join(parts) + ". Reaching PPO's full-profile final within these env "
        "steps (a periodic evaluation at or above it): " + "; ".join(full) + "."
    )


def ppo_values() -> dict:
    """The fine-tuned flows against PPO from its Gaussian clone: every seed, and point_mass's fresh seeds alone."""
    lines = [
        "| task | method (from its clone) | seeds | mean [95 % CI] (seeds) | P(method > PPO) [95 % CI] | |",
        "|---|---|---|---|---|---|",
    ]
    sentences = []
    for task in DMC_TASKS:
        ppo = group(DMC_KEPT, task, "ppo")
        _, fresh = chosen_and_fresh(task)
        for seeds in [None, fresh] if fresh else [None]:
            for label in FLOWS_HELD + ("ppo",):
                runs = [r for r in group(DMC_KEPT, task, label) if seeds is None or r.seed in seeds]
                if not runs:
                    continue
                ppo_runs = [r for r in ppo if seeds is None or r.seed in seeds]
                p = improvement_of(n10(runs), n10(ppo_runs))
                lines.append(
                    f"| {task} | {NAMES[label]} | {seeds_text(r.seed for r in runs)} | {interval_cell(n10(runs))} | "
                    + ("" if label == "ppo" else f"{p.text(2)} | {verdict(p, 'method', 'PPO')}")
                    + (" | |" if label == "ppo" else " |")
                )
    # the sentence: point_mass's fresh seeds, then reacher_easy
    task = "dmc_point_mass"
    chosen, fresh = chosen_and_fresh(task)
    ppo_fresh = n10(group(DMC_KEPT, task, "ppo"), fresh)
    beaten: list[str] = []
    split: list[str] = []
    above: list[str] = []
    for label in FLOWS_HELD:
        values = n10(group(DMC_KEPT, task, label), fresh)
        p = improvement_of(values, ppo_fresh)
        item = f"{prose(label)} ({span(values)})"
        (beaten if max(values) < min(ppo_fresh) else above if p.side > 0 else split).append(item)
    text = (
        f"On point_mass's fresh seeds {seeds_text(fresh)} (run after adaptive λ and ASPO were chosen on seeds "
        f"{seeds_text(chosen)}, which the all-seed rows pool with them) every PPO seed ({span(ppo_fresh)}) ends above "
        f"every seed of {and_list(beaten) if beaten else 'no method'}"
    )
    if split:
        text += f"; the seeds of {and_list(split)} mix with PPO's"
    if above:
        text += f"; {and_list(above)} ends above PPO"
    sentences.append(text + ".")
    task = "dmc_reacher_easy"
    reacher_ppo = n10(group(DMC_KEPT, task, "ppo"))
    rest = []
    for label in FLOWS_HELD:
        reacher_runs = group(DMC_KEPT, task, label)
        if reacher_runs:
            p = improvement_of(n10(reacher_runs), reacher_ppo)
            rest.append((prose(label), p))
    none = all(not p.separates for _, p in rest)
    sentences.append(
        f"On reacher_easy ({len(reacher_ppo)} seeds each) "
        + (
            f"no interval separates a flow method from PPO (P = {span([p.point for _, p in rest], 2)})."
            if none
            else "the intervals separate "
            + and_list([f"{n} ({p.text(2)})" for n, p in rest if p.separates])
            + " from PPO."
        )
    )
    return {"ppo_table": "\n".join(lines), "ppo_sentence": " ".join(sentences)}


def one_step_sentence() -> str:
    parts = []
    for task in DMC_TASKS:
        items = []
        for label in FLOWS_HELD:
            runs = group(DMC_KEPT, task, label)
            if not runs:
                continue
            e10, e1 = mean_estimate(tuple(n10(runs))), mean_estimate(tuple(r.n1 for r in runs))
            overlap = e1.low <= e10.high and e10.low <= e1.high
            where = "overlap" if overlap else ("N = 1 above" if e1.low > e10.high else "N = 1 below")
            items.append(f"{prose(label)} {e1.text()} against {e10.text()} ({where})")
        parts.append(f"on {task[4:]}: " + "; ".join(items))
    return "N = 1 against N = 10 after fine-tuning, " + "; ".join(parts) + "."
