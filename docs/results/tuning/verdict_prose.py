"""The page's sentences whose verdict depends on the data: the goal, the comparisons with PPO and with the paper's
values, what is adopted, the failures and the budget runs' reading, each chosen here from the numbers."""

from __future__ import annotations

import re

import numpy as np
from budget_curves import BudgetRun, curve_at, marks
from fresh_seeds import Fresh, Row, one_step_counts, own_name, passes, reach
from study_files import (
    BUDGET_FILE,
    CODE_NAMES,
    DMC_PROFILE,
    FLOWS,
    LABELS,
    TASKS,
    fmt,
    read_yaml,
    short,
    times_text,
)
from study_tables import _same, chosen, own_trial

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.phrases import and_list

# ------------------------------------------------------------------------------------------------ the prose
EXIT_NOTE = re.compile(r"exit codes \[([^\]]*)\]")


def exit_text(code: int) -> str:
    from refpo_warp.cli.guard import EXIT_NONFINITE

    if code == EXIT_NONFINITE:
        return f"{code} (training stopped on a non-finite loss)"
    if code < 0:
        return f"{code} (ended by signal {-code})"
    return f"{code} (see `docs/cli.md`)"


def versus(poi, own: str, above: float) -> str:
    """P(a tuned run beats a run at the method's own values), with the verdict its interval gives."""
    text = f"P(tuned > {own}) {poi.text(2)}"
    if poi.low > above:
        return f"{text}, its interval above {above:g}: the tuned values are better"
    if poi.high < above:
        return f"{text}, its interval below {above:g}: the {own} values are better"
    return f"{text}, its interval spanning {above:g}: the seeds do not separate the two"


def means_text(row: Row) -> str:
    return " / ".join(f"{e.point:.0f}" for e in row.per_task)


def against_paper(fresh: Fresh, label: str) -> str:
    """Where the tuned mean is above and where below the mean at the method's own values."""
    tuned, paper = fresh.rows[f"{label}/tuned"].per_task, fresh.rows[f"{label}/paper"].per_task
    higher = [
        f"{short(t)} ({a.point:.0f} against {b.point:.0f})" for t, a, b in zip(TASKS, tuned, paper) if a.point > b.point
    ]
    lower = [
        f"{short(t)} ({a.point:.0f} against {b.point:.0f})"
        for t, a, b in zip(TASKS, tuned, paper)
        if a.point <= b.point
    ]
    parts = ([f"higher on {and_list(higher)}"] if higher else []) + ([f"lower on {and_list(lower)}"] if lower else [])
    return "its mean is " + ", ".join(parts)


def runs_text(row: Row, task: str) -> str:
    out = []
    for seed, multi, one, failed in row.values(task):
        out.append(
            f"seed {seed} failed"
            if failed
            else f"seed {seed} {multi:.0f}" + (f" ({one:.0f})" if one is not None else "")
        )
    return ", ".join(out)


def range_text(row: Row, task: str) -> str:
    values = [multi for _, multi, _, _ in row.values(task)]
    return f"{min(values):.0f}-{max(values):.0f}"


def goal_parts(fresh: Fresh, crit: dict) -> dict:
    need, goal = crit["goal"]["reach_tasks"], crit["goal"]["one_step"]
    flows = [label for label in FLOWS if f"{label}/tuned" in fresh.rows]
    reached = {label: sum(reach(fresh, label)) for label in flows}
    meet_a = [label for label in flows if reached[label] >= need]
    row = fresh.rows.get(f"{goal['method']}/tuned")
    held, near, total, misses = one_step_counts(row, goal["share"], crit["report"]["within"]) if row else (0, 0, 0, [])
    meet_b = row is not None and held == total
    return {
        "reached": reached,
        "meet_a": meet_a,
        "held": held,
        "near": near,
        "total": total,
        "misses": misses,
        "meet_b": meet_b,
        "met": bool(meet_a) and meet_b,
        "need": need,
        "flows": flows,
    }


def goal_text(fresh: Fresh, crit: dict) -> str:
    g, ppo = goal_parts(fresh, crit), fresh.rows["ppo/tuned"]
    n = len(TASKS)
    per = ", ".join(f"{CODE_NAMES[label]} {g['reached'][label]} of {n}" for label in g["flows"])
    a = f"(a) Tasks where the tuned interval reaches tuned PPO's: {per}; "
    a += f"met by {and_list(CODE_NAMES[x] for x in g['meet_a'])}." if g["meet_a"] else "met by none."
    thin = []
    for label in g["meet_a"]:
        row = fresh.rows[f"{label}/tuned"]
        for task, e, q, ok in zip(TASKS, row.per_task, ppo.per_task, reach(fresh, label)):
            if ok and e.point < q.low:
                failed = sum(f for _, _, _, f in row.values(task))
                thin.append(
                    f"{CODE_NAMES[label]} on {short(task)} reaches it only through its interval's spread: its mean "
                    f"{e.point:.0f} lies below PPO's interval {q.text()}, its own interval is {e.text()} and its runs "
                    f"range {range_text(row, task)}"
                    + (f" ({failed} failed run{'s' if failed > 1 else ''} counted as 0)" if failed else "")
                )
    if thin:
        a += " " + "; ".join(thin) + "."
    method = CODE_NAMES[crit["goal"]["one_step"]["method"]]
    share = crit["goal"]["one_step"]["share"]
    b = f"(b) {method}'s N = 1 ≥ {share:g} × N = 10 holds in {g['held']} of {g['total']} runs"
    b += ": met." if g["meet_b"] else f", not in every run ({'; '.join(g['misses'])}): not met."
    verdict = "The goal is met." if g["met"] else "The goal is not met."
    return f"{a} {b} {verdict}"


def goal_summary(fresh: Fresh, crit: dict) -> str:
    g = goal_parts(fresh, crit)
    a = f"(a) is met by {and_list(CODE_NAMES[x] for x in g['meet_a'])}" if g["meet_a"] else "(a) is met by none"
    b = f"(b) {'is met' if g['meet_b'] else 'is not'} ({g['held']} of {g['total']} runs)"
    tail = "the goal is met" if g["met"] else "the goal is not met"
    return f"{a}, {b}: {tail}."


def vs_ppo_summary(fresh: Fresh, above: float) -> str:
    pois = fresh.vs_ppo
    listed = ", ".join(f"{CODE_NAMES[label]} {p.text(2)}" for label, p in pois.items())
    text = f"The probability that a tuned flow run beats a tuned PPO run on the same task: {listed}. "
    reaching = [CODE_NAMES[label] for label, p in pois.items() if p.high >= above]
    seeds = len(fresh.rows["ppo/tuned"].seeds)
    if all(p.high < above for p in pois.values()):
        text += f"Every interval lies below {above:g}: tuned PPO is the better choice at this budget."
    elif all(p.point < above for p in pois.values()):
        text += (
            f"Every point estimate is below {above:g} (PPO leads); the intervals of {and_list(reaching)} reach "
            f"{above:g}, so {seeds} seeds do not separate {'it' if len(reaching) == 1 else 'them'} from PPO."
        )
    else:
        at = [CODE_NAMES[label] for label, p in pois.items() if p.point >= above]
        text += f"The point estimate of {and_list(at)} is at or above {above:g}."
    most = max(sum(passes(fresh, label)) for label in pois)
    who = [CODE_NAMES[label] for label in pois if sum(passes(fresh, label)) == most]
    if most == 0:
        return text + " No tuned flow method's mean passes tuned PPO's on any task."
    return text + (
        f" A tuned flow method's mean passes tuned PPO's on at most {most} of {len(TASKS)} tasks ({and_list(who)})."
    )


def iqm_summary(fresh: Fresh) -> str:
    pairs = [label for label in LABELS if f"{label}/paper" in fresh.rows and f"{label}/tuned" in fresh.rows]
    text = ", ".join(
        f"{CODE_NAMES[label]} {fresh.iqm[f'{label}/paper'].point:.2f} → {fresh.iqm[f'{label}/tuned'].point:.2f}"
        for label in pairs
    )
    gain = max(pairs, key=lambda label: fresh.iqm[f"{label}/tuned"].point - fresh.iqm[f"{label}/paper"].point)
    flows = [label for label in FLOWS if label in pairs]
    best = max(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].point)
    narrow = min(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].high - fresh.iqm[f"{label}/tuned"].low)
    return (
        f"{text}; the largest rise is {CODE_NAMES[gain]}'s. The highest tuned flow IQM is {CODE_NAMES[best]}'s, "
        f"{fresh.iqm[f'{best}/tuned'].text(2)}; the narrowest tuned flow interval is {CODE_NAMES[narrow]}'s"
    )


def adoption(fresh: Fresh, crit: dict, profile: dict[str, dict]) -> tuple[str, str]:
    """(the summary sentence, the paragraph's verdicts) of the adoption rule."""
    above, picked, cpu = crit["adopt"]["above"], chosen(), read_yaml(DMC_PROFILE)["by_device"]["cpu"].get("by_algo", {})
    adopted, kept, notes = [], [], []
    for label, poi in fresh.vs_own.items():
        name, passed = CODE_NAMES[label], poi.low > above
        now = profile.get(label)
        if passed:
            adopted.append(label)
            if now is not None and label in picked and _same(now, picked[label]["overrides"]):
                where = (
                    f"`configs/task/_dmc.yaml`, `by_device.cpu.by_algo.{label}`" if label in cpu else "the CPU profile"
                )
                values = ", ".join(f"{k.rsplit('.', 1)[-1]} {fmt(v)}" for k, v in now.items())
                notes.append(
                    f"{name} passes ({poi.text(2)}): its chosen values are now its CPU profile's ({where}: {values})"
                )
            else:
                notes.append(f"{name} passes ({poi.text(2)}), but its CPU profile does not hold its chosen values yet")
        else:
            kept.append(label)
            own = own_trial(label)
            own_values = {k: float(own[k]) for k in (now or {})} if own and now else None
            if now is not None and own_values is not None and not _same(now, own_values):
                notes.append(
                    f"{name} does not pass ({poi.text(2)}), yet its CPU profile no longer holds its own values"
                )
            else:
                notes.append(f"{name} does not pass ({poi.text(2)}) and keeps its {own_name(label)} values")
    summary = (
        'By the adoption rule (see "Which values became the CPU profile\'s"), '
        + (
            f"{and_list(CODE_NAMES[x] for x in adopted)} now "
            + ("runs its" if len(adopted) == 1 else "run their")
            + " chosen values at the CPU profile"
            if adopted
            else "no method's chosen values replace its own"
        )
        + (f"; {and_list(CODE_NAMES[x] for x in kept)} keep their own." if kept and adopted else ".")
    )
    return summary, "; ".join(notes) + "."


def failures_text(fresh: Fresh) -> str:
    out = []
    for row in fresh.rows.values():
        if row.kind != "tuned":
            continue
        for (task, seed), note in sorted(row.runs.failed.items()):
            match = EXIT_NOTE.search(note)
            codes = [int(c) for c in re.findall(r"-?\d+", match.group(1))] if match else []
            attempts = ", then ".join(exit_text(c) for c in codes) if codes else "no exit code recorded"
            out.append(f"{short(task)}/{row.label}/seed{seed}: {len(codes)} attempt(s), exit code {attempts}")
    if not out:
        return "None."
    return (
        "; ".join(out)
        + ". The sweep's report keeps no more of a failed run than its exit codes and the path of its log, which is "
        "not committed: where training stopped and how large its ratios grew are not recorded here."
    )


def budget_prose(runs: list[BudgetRun], fresh: Fresh | None, profile: int, multiple: int, crit: dict) -> dict:
    fall = crit["report"]["fall"]
    spec = read_yaml(BUDGET_FILE)
    flow = next(m["label"] for m in spec["methods"] if m["label"] != "ppo")
    task = spec["tasks"][0]
    by = {label: [r for r in runs if r.label == label] for label in ("ppo", flow)}
    ks = marks(multiple)
    # the difference of the means as the curves table rounds them, so that the two agree
    leads = [round(curve_at(by["ppo"], k * profile)[0]) - round(curve_at(by[flow], k * profile)[0]) for k in ks]
    lead_list = ", ".join(f"{lead} at {k}×" for k, lead in zip(ks, leads))
    later = leads[1:]
    if later and all(x > leads[0] for x in later):
        verdict = "larger at every later multiple than at 1×"
    elif later and all(x < leads[0] for x in later):
        verdict = "smaller at every later multiple than at 1×"
    else:
        verdict = "not consistently larger or smaller than at 1×"
    falls = {label: sum(r.fell(fall) for r in rs) for label, rs in by.items()}
    stopped = sum(r.stop is not None for r in by[flow])
    text = (
        f"PPO's lead over {CODE_NAMES[flow]} (the difference of the means) is {lead_list}: {verdict}. "
        f"{CODE_NAMES[flow]}'s return ends below {fall:g} × its peak in {falls[flow]} of {len(by[flow])} seeds"
        + (f" ({stopped} of them stopped on a non-finite loss)" if stopped else "")
        + f", PPO's in {falls['ppo']} of {len(by['ppo'])}."
    )
    at1 = ", ".join(f"seed {r.seed} {np.interp(profile, r.steps, r.values):.0f}" for r in by[flow])
    fresh_text = ""
    if fresh is not None and f"{flow}/tuned" in fresh.rows:
        row = fresh.rows[f"{flow}/tuned"]
        fresh_text = (
            f"; its fresh {short(task)} runs at the same values and the profile's budget ended at "
            f"{runs_text(row, task)} (N = 10, N = 1 in brackets)"
        )
    best = None
    if fresh is not None:
        flows = [label for label in FLOWS if f"{label}/tuned" in fresh.rows]
        best = max(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].point)
    still = (
        "--"
        if best is None
        else "still the tuned flow method with the highest IQM on the fresh seeds"
        if best == flow
        else f"the tuned flow method with the highest IQM on the fresh seeds is now {CODE_NAMES[best]}"
    )
    ppo_lr = chosen().get("ppo", {}).get("overrides", {}).get("algorithm.learning_rate")
    own_ppo = own_trial("ppo")
    return {
        "budget_flow": CODE_NAMES[flow],
        "budget_flow_still": still,
        "budget_verdict": text,
        "budget_at_one": f"At 1× the budget runs of {CODE_NAMES[flow]} return {at1}{fresh_text}.",
        "budget_ppo_lr": (
            f"{fmt(ppo_lr)}, {times_text(ppo_lr / float(own_ppo['algorithm.learning_rate']))}× the paper's"
            if ppo_lr and own_ppo
            else "--"
        ),
        "budget_seeds": seeds_text({r.seed for r in runs}),
        "budget_task": short(task),
    }
