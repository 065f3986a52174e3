#!/usr/bin/env python
"""``search.md`` in this folder, written whole from ``search.template.md`` and the committed data files (nothing typed
in by hand):

    python docs/results/one_step/search_tables.py [--check]

Reads ``search/report/runs.csv`` (the one-step configuration's runs, ``onestep_c03`` of ``refpo sweep cpu_onestep``,
and ReFPO's and PPO's point_mass runs beside them), ``../cpu_dmc/runs.csv`` (ReFPO's and PPO's runs on every task),
the screen's ``search/screen_*.json`` (``one_step_analysis.py screen=...``), ``configs/sweep/cpu_onestep.yaml`` (the
candidates, tasks and seeds), ``configs/algo/refpo_onestep.yaml``, the learning check's records
(``docs/results/learning_checks/records/point_mass_refpo_onestep.jsonl``) and its bounds (``tests/learning/checks.py``),
and the thresholds of ``criteria.yaml``. Every table and every count follows the seeds the files hold.

The helpers it shares with ``one_step_analysis.py --page``, which writes ``README.md`` (rows of a runs.csv, means,
ranges, intervals), are in ``run_rows.py``.
"""

from __future__ import annotations

import itertools
import json
import statistics
import sys
from pathlib import Path

import yaml
from run_rows import (
    CPU_DMC_RUNS,
    HERE,
    MULTI,
    ONE,
    RESULTS,
    ROOT,
    collapsed,
    criteria,
    interval_text,
    intervals,
    labels_of,
    listing,
    method_names,
    of,
    per_seed,
    pm,
    read_rows,
    separated,
    short,
    signed_pct,
    span,
    sweep_spec,
    tasks_of,
)

sys.path.insert(0, str(ROOT))  # refpo_warp, when run from anywhere

from refpo_warp.studies.reports.committed_runs import read_jsonl, seeds_text
from refpo_warp.studies.reports.phrases import and_list
from refpo_warp.studies.reports.results_page import main_args, write_page
from refpo_warp.utils.errors import DataFileError

SEARCH_RUNS = HERE / "search" / "report" / "runs.csv"
SWEEP = ROOT / "configs" / "sweep" / "cpu_onestep.yaml"
ONESTEP_ALGO = ROOT / "configs" / "algo" / "refpo_onestep.yaml"
RECORDS = RESULTS / "learning_checks" / "records" / "point_mass_refpo_onestep.jsonl"
CHECK = "point_mass_refpo_onestep"


# ------------------------------------------------------------------------------------------------ the page
def screen_results() -> tuple[dict, list[Path]]:
    """{'iteration', 'iterations', 'seeds': {seed: result}} merged over the screen's JSON files, and the files."""
    files = sorted((HERE / "search").glob("screen_*.json"))
    merged: dict = {"seeds": {}}
    for path in files:
        data = json.loads(path.read_text(encoding="utf-8"))
        for key in ("iteration", "iterations"):
            if merged.setdefault(key, data[key]) != data[key]:
                raise SystemExit(f"{path}: {key} {data[key]} differs from the other screen files' {merged[key]}")
        merged["seeds"].update({int(s): r for s, r in data["seeds"].items()})
    merged["seeds"] = dict(sorted(merged["seeds"].items()))
    return merged, files


def screen_values(screen: dict, spec: dict) -> dict:
    seeds = list(screen["seeds"])
    results = screen["seeds"]
    rule = "ReFPO (the paper's rule)"
    candidates = [m for m in spec["methods"] if m["label"] not in ("refpo", "ppo")]
    names = [m["name"] for m in candidates]

    def err(seed, name):
        return results[seed]["variants"][name]["states_N"]["one_step_error"]

    def ret(seed, name, n):
        return results[seed]["variants"][name]["returns"][n]

    def cell(r):
        return f"{r['states_N']['one_step_error']:.3f}, {r['returns']['N=10']:.0f} / {r['returns']['N=1']:.0f}"

    header = "| candidate | " + " | ".join(f"seed {s}: error, N=10 / N=1" for s in seeds) + " |"
    lines = [header, "|---|" + "---|" * len(seeds)]
    lines.append(
        f"| checkpoint (iteration {screen['iteration']}) | "
        + " | ".join(cell(results[s]["checkpoint"]) for s in seeds)
        + " |"
    )
    for name in [rule, *names]:
        lines.append(f"| {name} | " + " | ".join(cell(results[s]["variants"][name]) for s in seeds) + " |")

    start = [results[s]["checkpoint"]["returns"] for s in seeds]
    share = [r["N=1"] / r["N=10"] for r in start]
    before = (
        f"before the collapse: the checkpoint's 1-step return is {span(share, 2)} × its 10-step return"
        if min(share) >= criteria()["collapse_below"]
        else "where some seed's 1-step return has already collapsed"
    )

    # The findings, each from the numbers it states.
    findings = []
    coef = {
        m["name"]: m["overrides"]["algorithm.one_step_coef"]
        for m in candidates
        if set(m.get("overrides", {})) == {"algorithm.one_step_coef"}
    }
    ordered = sorted(coef, key=coef.__getitem__)
    factors = {n: [err(s, rule) / err(s, n) for s in seeds] for n in ordered}
    monotone = all(err(s, a) > err(s, b) for s in seeds for a, b in itertools.pairwise(ordered))
    largest = ordered[-1]
    drop = [ret(s, rule, "N=10") - ret(s, largest, "N=10") for s in seeds]
    coupled = [
        m["name"]
        for m in candidates
        if m.get("overrides") == {"algorithm.reflow_pairs": "coupled", "algorithm.reflow_coef": 0.2}
    ]
    coupled_text = ""
    if coupled:
        c = coupled[0]
        coupled_text = (
            f", against {span([err(s, rule) / err(s, c) for s in seeds], 1)}× for {c}, which costs a second pass of "
            "the network over the pairs"
        )
    findings.append(
        "- **The one-step term acts directly"
        + (" and in proportion**" if monotone else "**")
        + ": against ReFPO's rule after the same iterations it divides the error by "
        + ", ".join(f"{span(factors[n], 1)}× at {coef[n]:g}" for n in ordered)
        + coupled_text
        + ("; in every seed a larger coefficient leaves a smaller error" if monotone else "")
        + f". At {coef[largest]:g} the 10-step return ends {span(drop, 0)} below ReFPO's rule's within these iterations"
        + " (our reading: the term then competes with the surrogate)."
    )

    by_overrides = {json.dumps(m.get("overrides", {}), sort_keys=True): m["name"] for m in candidates}
    tau0 = [m for m in candidates if m.get("overrides", {}).get("algorithm.reflow_tau_weight") == "towards_zero"]
    pairs = []
    for m in tau0:
        without = {k: v for k, v in m["overrides"].items() if k != "algorithm.reflow_tau_weight"}
        twin = by_overrides.get(json.dumps(without, sort_keys=True))
        pairs.append((m["name"], twin))
    for name, twin in pairs:
        if twin is not None:
            lower = sum(err(s, name) < err(s, twin) for s in seeds)
            findings.append(
                f"- **Weighting the Reflow term towards τ = 0** ({name}) against the same rule unweighted: "
                "lower error in "
                f"{of(lower, len(seeds))} seeds ({listing([err(s, name) for s in seeds], 3)} against "
                f"{listing([err(s, twin) for s in seeds], 3)})."
            )
        else:
            lower = sum(err(s, name) < err(s, rule) for s in seeds)
            findings.append(
                f"- **{name}**: lower error than ReFPO's rule in {of(lower, len(seeds))} seeds "
                f"({listing([err(s, name) for s in seeds], 3)} against {listing([err(s, rule) for s in seeds], 3)}); "
                "it changes λ as well as the weighting and the screen has no unweighted twin, so it cannot separate "
                "the two. The independent term's minimiser sends one step to the mean action whatever its weighting "
                "(`one_step_probes.py`), which predicts little from the weighting alone."
            )

    adaptive = [m for m in candidates if m.get("overrides", {}).get("algorithm.reflow_schedule") == "adaptive"]
    for m in adaptive:
        low, high = m["overrides"]["algorithm.reflow_coef_range"]
        name = m["name"]
        findings.append(
            f"- **{name}**: error {listing([err(s, name) for s in seeds], 3)} against ReFPO's rule's "
            f"{listing([err(s, rule) for s in seeds], 3)}. Its λ stays in [{low:g}, {high:g}] and moves only "
            "when the one-step "
            "ratio leaves its band; whether it moved in these iterations is not in the screen's files, so the screen "
            "cannot rank it; its whole-run behaviour (with the default range) is in `README.md` here."
        )

    ema = [m for m in candidates if "algorithm.ema_decay" in m.get("overrides", {})]
    for m in ema:
        without = {k: v for k, v in m["overrides"].items() if k != "algorithm.ema_decay"}
        twin = by_overrides.get(json.dumps(without, sort_keys=True))
        if twin is None:
            continue
        more = sum(err(s, m["name"]) > err(s, twin) for s in seeds)
        findings.append(
            f"- **The EMA actor** ({m['name']}) leaves more error than the same term without it in "
            f"{of(more, len(seeds))} seeds ({span([err(s, m['name']) for s in seeds], 3)} against "
            f"{span([err(s, twin) for s in seeds], 3)}): "
            + ("it is not a remedy here." if more == len(seeds) else "the screen does not rank it.")
        )

    commands = []
    for path in sorted((HERE / "search").glob("screen_*.json")):
        data = json.loads(path.read_text(encoding="utf-8"))
        for seed in sorted(int(s) for s in data["seeds"]):
            commands.append(seed)
    first = commands[0] if commands else 1
    command = (
        "python docs/results/one_step/one_step_analysis.py runs/sweeps/cpu_reflow_pairs task=dmc_point_mass "
        f"seed={first} \\\n    screen=cpu_onestep intervene={screen['iteration']} "
        f"intervene_iterations={screen['iterations']} out=docs/results/one_step/search"
        + (f"   # then seed={', seed='.join(str(s) for s in commands[1:])}" if commands[1:] else "")
    )
    return {
        "n_candidates": len(candidates),
        "screen_seeds": seeds_text(seeds),
        "screen_iterations": screen["iterations"],
        "screen_iteration": screen["iteration"],
        "screen_before": before,
        "screen_commands": command,
        "screen_table": "\n".join(lines),
        "screen_findings": "\n".join(findings),
    }


def full_run_values(spec: dict, rules: dict) -> dict:
    rows, dmc = read_rows(SEARCH_RUNS), read_rows(CPU_DMC_RUNS)
    names = method_names(spec)
    full = [label for label in labels_of(rows) if label not in ("refpo", "ppo")]
    label = full[0]
    tasks = [t for t in spec["tasks"] if t in tasks_of(rows, label)]
    goal = rules["goal"]
    share = goal["one_step_share"]

    mine = {t: (per_seed(rows, label, t, MULTI), per_seed(rows, label, t, ONE)) for t in tasks}
    refpo = {t: (per_seed(dmc, "refpo", t, MULTI), per_seed(dmc, "refpo", t, ONE)) for t in tasks}
    ppo = {t: per_seed(dmc, "ppo", t, MULTI) for t in tasks}
    seeds = sorted({s for t in tasks for s in mine[t][0]})
    est = intervals(
        {f"{who}:{t}": list(src[t][0].values()) for t in tasks for who, src in (("mine", mine), ("refpo", refpo))}
    )

    lines = [
        "| task | "
        + " | ".join(f"seed {s}: 10-step / 1-step" if i == 0 else f"seed {s}" for i, s in enumerate(seeds))
        + f" | 1-step ≥ {share:g} × 10-step | 10-step mean [95 %] | ReFPO's (`cpu_dmc`, seeds {{}}) | change |",
        "|---|" + "---|" * (len(seeds) + 4),
    ]
    refpo_seed_sets = sorted({seeds_text(refpo[t][0]) for t in tasks})
    lines[0] = lines[0].replace("{}", ", ".join(refpo_seed_sets))
    held_all, pairs_all, changes, overlap = 0, 0, {}, []
    narrowest: tuple[float, str, int, float, float] | None = None  # (1-step / 10-step, task, seed, 1-step, 10-step)
    for t in tasks:
        multi, one = mine[t]
        cells = [f"{multi[s]:.0f} / {one[s]:.0f}" if s in multi and s in one else "--" for s in seeds]
        held = [s for s in multi if s in one and one[s] >= share * multi[s]]
        held_all += len(held)
        pairs_all += len(multi)
        for s in multi:
            if s in one and multi[s] > 0:
                ratio = one[s] / multi[s]
                if narrowest is None or ratio < narrowest[0]:
                    narrowest = (ratio, t, s, one[s], multi[s])
        a, b = est[f"mine:{t}"], est[f"refpo:{t}"]
        change = a.point / b.point - 1.0
        changes[t] = change
        if not separated(a, b):
            overlap.append(short(t))
        lines.append(
            f"| {short(t)} | "
            + " | ".join(cells)
            + f" | {of(len(held), len(multi))} | {interval_text(a)} | {interval_text(b)} | {signed_pct(change)} |"
        )

    drop = goal["ten_step_drop"]
    within = [t for t in tasks if changes[t] >= -drop]
    if len(overlap) == len(tasks):
        failing = [short(t) for t in tasks if t not in within]
        verdict = (
            "On every task the two intervals overlap: these seeds do not separate the one-step configuration's "
            "10-step return from ReFPO's in either direction, "
            + (
                f"so the goal's {100 * drop:g} % bound is met on the means only."
                if not failing
                else f"and on the means the goal's {100 * drop:g} % bound fails on {and_list(failing)}."
            )
        )
    else:
        apart = [short(t) for t in tasks if short(t) not in overlap]
        verdict = (
            f"The intervals are apart on {and_list(apart)}"
            + (f" and overlap on {and_list(overlap)}" if overlap else "")
            + "."
        )

    # ReFPO's standing on cpu_dmc, with the same share.
    r_held = sum(1 for t in tasks for s, m in refpo[t][0].items() if s in refpo[t][1] and refpo[t][1][s] >= share * m)
    r_pairs = sum(len(refpo[t][0]) for t in tasks)
    below = rules["collapse_below"]
    parts = []
    for t in tasks:
        m, o = refpo[t]
        k = sum(collapsed(m[s], o[s], below) for s in m if s in o)
        if k:
            parts.append(
                f"on {short(t)} the 1-step return collapses in {of(k, len(m))} seeds (10-step {pm(m.values())}, "
                f"1-step {pm(o.values(), 1)})"
            )
    standing = (
        f"the 1-step return is at least {share:g} × the 10-step return in {of(r_held, r_pairs)} (task, seed) pairs"
    )
    standing += ("; " + "; ".join(parts) + ".") if parts else "."

    # Where the goal stands.
    mean_one = {t: statistics.fmean(mine[t][1].values()) for t in tasks}
    mean_ppo = {t: statistics.fmean(ppo[t].values()) for t in tasks if ppo[t]}
    at_ppo = [t for t in tasks if t in mean_ppo and mean_one[t] >= mean_ppo[t]]
    need = goal["ppo_tasks"]
    if narrowest is None:
        raise DataFileError(
            f"{SEARCH_RUNS}: no finished run with a positive 10-step return to compare its 1-step one with"
        )
    ratio, nt, ns, n1, n10 = narrowest
    goal_rows = [
        "| criterion | shown? |",
        "|---|---|",
        (
            f"| 1-step ≥ {share:g} × 10-step in every (task, seed) | **{'yes' if held_all == pairs_all else 'no'}, "
            f"{of(held_all, pairs_all)}** (ReFPO: {of(r_held, r_pairs)}); the narrowest: {short(nt)} seed {ns}, "
            f"{n1:.0f} against {n10:.0f} ({ratio:.2f}) |"
        ),
        f"| 10-step mean within {100 * drop:g} % of ReFPO's, per task | "
        + ("**yes, on the means**: " if len(within) == len(tasks) else "**no**: ")
        + ", ".join(f"{signed_pct(changes[t])} ({short(t)})" for t in tasks)
        + ("; not separated from ReFPO's by these seeds" if len(overlap) == len(tasks) else "")
        + " |",
        (
            f"| update ≤ {goal['update_cost']:g} × ReFPO's, aiming at {goal['update_cost_aim']:g} × | not recorded "
            'in a data file here: `docs/algorithms.md`, "Update time", has the `refpo bench algorithms` measurement |'
        ),
        (
            f"| 1-step return ≥ PPO's on at least {need} tasks | **{'yes' if len(at_ppo) >= need else 'no'}** "
            f"({of(len(at_ppo), len(mean_ppo))}): {listing(mean_one[t] for t in tasks)} against PPO's "
            f"{listing(mean_ppo[t] for t in tasks if t in mean_ppo)} ({' / '.join(short(t) for t in tasks)}) |"
        ),
    ]

    # ReFPO and PPO beside it on point_mass.
    side = [lb for lb in ("refpo", "ppo") if lb in labels_of(rows)]
    pm_task = "dmc_point_mass"
    table = [
        f"| {short(pm_task)}, seeds | 10-step (PPO: mean action) | 1-step | 10-step / 1-step from zero noise |",
        "|---|---|---|---|",
    ]
    for lb in [label, *side]:
        values = {k: per_seed(rows, lb, pm_task, k) for k in (MULTI, ONE, "return_multi_zero", "return_1_zero")}
        if not values[MULTI]:
            continue
        digits = 1 if values[ONE] and statistics.fmean(values[ONE].values()) < 100 else 0

        def cell(v, d=0):
            return pm(v.values(), d) if v else "-"

        zero = (
            f"{cell(values['return_multi_zero'])} / {cell(values['return_1_zero'], digits)}"
            if values["return_multi_zero"]
            else "-"
        )
        table.append(
            f"| {names.get(lb, lb)}, `{lb}`, seeds {seeds_text(values[MULTI])} | {cell(values[MULTI])} | "
            f"{cell(values[ONE], digits)} | {zero} |"
        )
    one_pm = per_seed(rows, label, pm_task, ONE)
    multi_pm = per_seed(rows, label, pm_task, MULTI)
    refpo_one = per_seed(rows, "refpo", pm_task, ONE)
    ppo_multi = per_seed(rows, "ppo", pm_task, MULTI)
    e = intervals(
        {
            "one": list(one_pm.values()),
            "refpo_one": list(refpo_one.values()),
            "multi": list(multi_pm.values()),
            "ppo": list(ppo_multi.values()),
        }
    )
    pm_verdict = (
        f"With 95 % intervals: the one-step configuration's 1-step return {interval_text(e['one'])} against ReFPO's "
        f"{interval_text(e['refpo_one'], 1)} ("
        + ("apart" if separated(e["one"], e["refpo_one"]) else "overlapping")
        + f"); its 10-step return {interval_text(e['multi'])} against Gaussian PPO's {interval_text(e['ppo'])} ("
        + (
            "apart: PPO's is higher"
            if separated(e["multi"], e["ppo"]) and e["ppo"].point > e["multi"].point
            else "apart"
            if separated(e["multi"], e["ppo"])
            else "overlapping"
        )
        + ")."
    )

    # Bit-identical to cpu_dmc?
    checked, same = 0, 0
    for lb in side:
        for r in rows:
            if r["label"] != lb or r["task"] != pm_task:
                continue
            twin = [d for d in dmc if d["label"] == lb and d["task"] == pm_task and d["seed"] == r["seed"]]
            if twin:
                checked += 1
                same += all(r[k] == twin[0][k] for k in (MULTI, ONE) if k in twin[0])
    refpo_multi_pm = per_seed(rows, "refpo", pm_task, MULTI)
    if checked and same == checked:
        bits = (
            f"their final returns equal those of `cpu_dmc`'s runs of the same seeds to the last digit in "
            f"{of(same, checked)} runs (ReFPO's N = 10 returns {listing(refpo_multi_pm.values())}), as bit-identical "
            "training would give"
        )
    else:
        bits = f"their final returns equal those of `cpu_dmc`'s runs of the same seeds in {of(same, checked)} runs"
    minutes = [float(r["minutes"]) for r in rows if r["label"] in side and r["task"] == pm_task and r.get("minutes")]

    algo = yaml.safe_load(ONESTEP_ALGO.read_text(encoding="utf-8"))
    method = next(m for m in spec["methods"] if m["label"] == label)
    flat_algo = {f"algorithm.{k}": v for k, v in algo.get("algorithm", {}).items()}
    same_algo = algo.get("base") == method.get("algo") and flat_algo == method.get("overrides", {})
    equivalence = "the same options as `algo=refpo_onestep`" if same_algo else "not `algo=refpo_onestep`'s options"

    return {
        "tasks": ", ".join(short(t) for t in spec["tasks"]),
        "sweep_seeds": seeds_text(spec["seeds"]),
        "share": f"{share:g}",
        "drop_pct": f"{100 * drop:g}",
        "cost": f"{goal['update_cost']:g}",
        "cost_aim": f"{goal['update_cost_aim']:g}",
        "collapse": f"{below:g}",
        "refpo_seeds": ", ".join(refpo_seed_sets),
        "refpo_standing": standing,
        "full_labels": ", ".join(f"`{lb}`" for lb in full),
        "full_labels_plain": ",".join(full),
        "algo_equivalence": equivalence,
        "n_full_runs": sum(len(mine[t][0]) for t in tasks),
        "full_runs_table": "\n".join(lines),
        "full_runs_verdict": verdict,
        "n_side_runs": sum(1 for r in rows if r["label"] in side),
        "bit_identical": bits,
        "side_minutes": span(minutes, 1),
        "point_mass_table": "\n".join(table),
        "point_mass_verdict": pm_verdict,
        "goal_table": "\n".join(goal_rows),
    }


def check_values() -> dict:
    """The learning check's bounds (tests/learning/checks.py) and its records with the check's present overrides."""
    sys.path.insert(0, str(ROOT / "tests" / "learning"))
    from checks import CHECKS  # tests/learning/checks.py

    check = CHECKS[CHECK]
    records = read_jsonl(RECORDS)
    current = [r for r in records if tuple(r["overrides"]) == tuple(check.overrides)]
    latest: dict[tuple, dict] = {}
    for r in current:  # the last record of each (null, threads, seed)
        latest[(r["null"], r["threads"], r["seed"])] = r
    groups: dict[tuple, list[dict]] = {}
    for key in sorted(latest, key=lambda k: (k[0], k[1], k[2])):
        groups.setdefault(key[:2], []).append(latest[key])

    def stats(r):
        return check.statistics(r)

    rise, ratio = check.bounds
    lines = [
        (
            f"| runs | N = 10 rise over the initial policy (bound ≥ {rise.value:g}) | N = 1 / N = 10 "
            f"(bound ≥ {ratio.value:g}) | wall time |"
        ),
        "|---|---|---|---|",
    ]
    for (null, threads), group in groups.items():
        what = "null control" if null else "learning"
        thread = f", {threads} thread{'s' if threads > 1 else ''}"
        lines.append(
            f"| {what}, seeds {seeds_text(r['seed'] for r in group)}{thread} | "
            + " / ".join(
                f"{stats(r)[rise.statistic]:.1f}" if null else f"{stats(r)[rise.statistic]:.0f}" for r in group
            )
            + " | "
            + " / ".join(f"{stats(r)[ratio.statistic]:.3f}" for r in group)
            + f" | {span([r['wall_s'] for r in group], 0)} s |"
        )
    learning = [r for (null, _), g in groups.items() if not null for r in g]
    nulls = [r for (null, _), g in groups.items() if null for r in g]
    both = sum(all(b.holds(stats(r)) for b in check.bounds) for r in learning)
    fails_rise = sum(not rise.holds(stats(r)) for r in nulls)
    ratio_alone = [r for r in nulls if ratio.holds(stats(r))]
    verdict = f"{of(both, len(learning))} learning runs meet both bounds"
    if nulls:
        verdict += f"; the null control fails the first in {of(fails_rise, len(nulls))} seeds" + (
            " and meets the ratio alone in seed "
            + ", ".join(
                f"{r['seed']} ({r['final']['N=1']['return_mean']:.1f} against {r['final']['N=10']['return_mean']:.1f})"
                for r in ratio_alone
            )
            + ", which is why the ratio is not the check's only bound."
            if ratio_alone
            else "."
        )
    else:
        verdict += "."

    earlier = [r for r in records if tuple(r["overrides"]) != tuple(check.overrides)]
    matched, equal = 0, 0
    for r in latest.values():
        twins = [e for e in earlier if (e["null"], e["threads"], e["seed"]) == (r["null"], r["threads"], r["seed"])]
        if twins:
            matched += 1
            equal += stats(twins[-1]) == stats(r)
    extra = sorted(set(check.overrides) - {o for e in earlier for o in e["overrides"]})
    if matched:
        rerecorded = (
            "The records above were made again that way, with "
            f"{', '.join(f'`{o}`' for o in extra) or 'the same overrides'}; "
            f"of the {matched} that have an earlier record of the same seed, threads and control, {equal} have every "
            "statistic equal to it."
        )
    else:
        rerecorded = ""
    cpus = sorted({r.get("cpu", "not recorded") for r in latest.values()})
    episodes = sorted({r["final"]["N=10"]["episodes"] for r in latest.values()})
    bounds = (
        f"the N = 10 return must rise at least {rise.value:g} above the initial policy's, and the N = 1 return must "
        f"be at least {ratio.value:g} × the N = 10 return"
    )
    return {
        "in_ci": ", in CI" if check.in_ci else "",
        "check_episodes": ", ".join(str(e) for e in episodes),
        "check_bounds": bounds,
        "check_cpu": ", ".join(cpus),
        "check_table": "\n".join(lines),
        "check_verdict": verdict,
        "rerecorded": rerecorded,
    }


def values() -> dict:
    rules = criteria()
    spec = sweep_spec(SWEEP)
    screen, files = screen_results()
    out = screen_values(screen, spec)
    out["screen_files"] = ", ".join(f"`search/{p.name}`" for p in files)
    out.update(full_run_values(spec, rules))
    out.update(check_values())
    return out


def main() -> int:
    args = main_args(__doc__.splitlines()[0]).parse_args()
    same = write_page(HERE / "search.template.md", values(), check=args.check)
    if args.check:
        return 0 if same else 1
    print(f"{HERE / 'search.md'}: {'unchanged' if same else 'written'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
