"""The FPO++ page's tables and generated prose, from the data ``fpo_pp_runs.py`` reads (``make_page.py`` writes the
page)."""

from __future__ import annotations

import dataclasses
import re
import statistics

import numpy as np
from fpo_pp_runs import (
    AUTHORS,
    CLIP_LABELS,
    CRITERIA,
    DMC_PROFILE,
    GPU,
    REPORT,
    ROOT,
    SETTINGS,
    SMALL,
    TASKS,
    TUNED_KEY,
    UNRECORDED_MACHINE,
    Method,
    cell,
    flat,
    fmt_value,
    num,
    poi,
    read_rows,
    run_config,
    short,
    short_verdict,
    sweep_spec,
)

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import read_jsonl, run_machine, seeds_text
from refpo_warp.studies.reports.phrases import and_list, machine_text, value_range
from refpo_warp.utils.errors import DataFileError


# ------------------------------------------------------------------------------------------------ tables
def settings_table(ms: dict[str, Method], data: dict) -> str:
    lines = [
        "| task | FPO++ at | seeds | N = 10 | N = 1 | N = 64, zero noise |",
        "|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        for key in (AUTHORS, SMALL, TUNED_KEY):
            runs = data[key]
            seeds = set().union(*(set(runs[s][task]) for s in ("multi", "one", "headline")))
            cells = [cell(runs[s][task]) for s in ("multi", "one", "headline")]
            lines.append(
                f"| {short(task)} | {ms[key].name} | {seeds_text(seeds) if seeds else 'no runs yet'} | "
                + " | ".join(cells)
                + " |"
            )
    return "\n".join(lines)


def all_table(ms: dict[str, Method], data: dict) -> str:
    lines = [
        "| task | method | seeds | N = 10 | N = 1 | N = 10, zero noise | N = 64, zero noise | file |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        for key, m in ms.items():
            runs = data[key]
            seeds = set().union(*(set(runs[s][task]) for s in SETTINGS))
            if not seeds:
                continue
            cells = [cell(runs[s][task]) for s in SETTINGS]
            lines.append(
                f"| {short(task)} | {m.name} | {seeds_text(seeds)} | " + " | ".join(cells) + f" | {m.source} |"
            )
    return "\n".join(lines)


def poi_rows(pairs, ms, data, settings=("multi", "headline")) -> tuple[list[str], list[tuple]]:
    """Table rows for each (x over y) pair, per task and over the three tasks; and (x, y, task, setting, p) kept."""
    rows, kept = [], []
    for x, y, label in pairs:
        for task in (*TASKS, None):
            ps = {s: poi(data[x][s], data[y][s], task) for s in settings}
            if all(p is None for p in ps.values()):
                continue
            where = short(task) if task else "the three tasks"
            if any(p is not None and not p.compared for p in ps.values()):
                dashes = " | ".join("--" for _ in settings)
                rows.append(f"| {where} | {label[0]} over {label[1]} | {dashes} | one seed on a side: not compared |")
                continue
            cells = []
            for s in settings:
                p = ps[s]
                cells.append("--" if p is None else f"{p.text(2)}")
                if p is not None:
                    kept.append((x, y, task, s, p))
            says = "; ".join(
                f"{SETTINGS[s][1]}: {short_verdict(p, *label)}" for s in settings if (p := ps[s]) is not None
            )
            rows.append(f"| {where} | {label[0]} over {label[1]} | " + " | ".join(cells) + f" | {says} |")
    return rows, kept


def poi_table(rows: list[str], settings=("multi", "headline")) -> str:
    head = "| where | comparison | " + " | ".join(f"P(improvement) [95 %], {SETTINGS[s][1]}" for s in settings)
    return "\n".join([head + " | what it says |", "|---|---|" + "---|" * len(settings) + "---|", *rows])


def small_verdicts(kept: list[tuple], ms: dict[str, Method]) -> str:
    """One sentence per comparison of the small recipe: where its runs beat, lose, or the seeds do not separate."""
    out = []
    shown = {AUTHORS: "the locomotion defaults", TUNED_KEY: "the tuned values"}
    for y in (AUTHORS, TUNED_KEY):
        parts = []
        for s in ("multi", "headline"):
            got = {task: p for x_, y_, task, s_, p in kept if x_ == SMALL and y_ == y and s_ == s}
            if not got:
                continue
            groups: dict[int, list[str]] = {1: [], -1: [], 0: []}
            for task, p in got.items():
                groups[p.side].append("over the three tasks" if task is None else f"on {short(task)}")
            bits = []
            if groups[1]:
                bits.append("its runs beat them " + and_list(groups[1]))
            if groups[-1]:
                bits.append("theirs beat it " + and_list(groups[-1]))
            if groups[0]:
                bits.append("the seeds do not separate them " + and_list(groups[0]))
            parts.append(f"at {SETTINGS[s][1]}, " + "; ".join(bits))
        if parts:
            out.append(f"- **The small-task recipe against {shown[y]}**: " + "; ".join(parts) + ".")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------ the page's parts
def sweep_text(ms: dict[str, Method]) -> dict[str, str]:
    """What configs/sweep/cpu_fpo_pp.yaml does now, checked against the CPU profile and the committed runs."""
    spec = sweep_spec()
    by_label = {m["label"]: m for m in spec["methods"]}
    authors = dict(by_label[AUTHORS].get("overrides") or {})
    on_authors, own = [], []
    for label, m in by_label.items():
        over = m.get("overrides") or {}
        if not all(k in over for k in authors):
            own.append(f"`{label}`")
            continue
        text = f"`{label}`"
        changed = [f"`{k}: {fmt_value(over[k])}`" for k in authors if over[k] != authors[k]]
        extra = [f"`{k}: {fmt_value(x)}`" for k, x in over.items() if k not in authors]
        if changed:
            text += " but " + ", ".join(changed)
        if extra:
            text += " plus " + ", ".join(extra)
        on_authors.append(text)
    profile = flat(load_yaml(DMC_PROFILE)["by_device"]["cpu"]["by_algo"][AUTHORS])
    same_keys = set(profile) == set(authors)
    held = []
    for task in TASKS:
        cfg = run_config(ms[AUTHORS], task)
        if cfg is not None:
            held.append(all(cfg.get(k) == v for k, v in authors.items()))
    tuned = {}
    for task in TASKS:
        cfg = run_config(ms[TUNED_KEY], task)
        if cfg is not None:
            tuned = cfg
            break
    tuned_match = all(tuned.get(k) == v for k, v in profile.items())
    return {
        "pinned_values": ", ".join(f"`{k}: {fmt_value(v)}`" for k, v in authors.items()),
        "profile_values": ", ".join(f"`{k}: {fmt_value(v)}`" for k, v in profile.items()),
        "profile_keys_note": (
            "the same keys" if same_keys else f"keys {sorted(set(profile) ^ set(authors))} differ between the two"
        ),
        "on_authors": "; ".join(on_authors),
        "own_labels": ", ".join(own) if own else "none",
        "runs_hold": (
            "the committed `fpo_pp` runs' `config.yaml` hold the pinned values"
            if held and all(held)
            else "the committed `fpo_pp` runs' `config.yaml` do not all hold the pinned values"
        ),
        "tuned_hold": (
            "the tuned runs' `config.yaml` hold the profile's values"
            if tuned and tuned_match
            else "the tuned runs' `config.yaml` do not hold the profile's values"
        ),
    }


def what_ran() -> tuple[str, str]:
    """Per label of report/runs.csv: tasks, seeds, runs; and the labels of the sweep file with no row yet."""
    rows = read_rows(REPORT)
    spec = sweep_spec()
    parts = []
    for m in spec["methods"]:
        mine = [r for r in rows if r["label"] == m["label"]]
        if not mine:
            continue
        tasks = sorted({r["task"] for r in mine}, key=TASKS.index)
        by_task = {t: sorted({int(r["seed"]) for r in mine if r["task"] == t}) for t in tasks}

        def seeds_of(seeds: list[int]) -> str:
            return f"seed{'s' if len(seeds) > 1 else ''} {seeds_text(seeds)}"

        if len(set(map(tuple, by_task.values()))) == 1:  # the same seeds on every task
            where = "the three tasks" if len(tasks) == len(TASKS) else ", ".join(short(t) for t in tasks)
            ran = f"on {where}, {seeds_of(by_task[tasks[0]])}"
        else:
            ran = ", ".join(f"on {short(t)} {seeds_of(seeds)}" for t, seeds in by_task.items())
        failed = sum(r["status"] == "failed" for r in mine)
        parts.append(
            f"`{m['label']}` {ran} ({len(mine)} run{'s' if len(mine) > 1 else ''}"
            + (f", {failed} failed" if failed else "")
            + ")"
        )
    missing = [f"`{m['label']}`" for m in spec["methods"] if not any(r["label"] == m["label"] for r in rows)]
    return "; ".join(parts), (", ".join(missing) if missing else "none")


def run_times() -> str:
    """Per label of report/runs.csv: its runs' wall times by the machine each recorded."""
    rows = read_rows(REPORT)
    by_machine: dict[str, dict[str, list[float]]] = {}
    for m in sweep_spec()["methods"]:
        for r in (r for r in rows if r["label"] == m["label"]):
            where = machine_text(run_machine(ROOT / r["run_dir"]), UNRECORDED_MACHINE)
            by_machine.setdefault(where, {}).setdefault(m["label"], []).append(float(r["minutes"]))
    return "; ".join(
        f"on {where}, " + ", ".join(f"`{label}` {value_range(minutes, '.0f')} min" for label, minutes in labels.items())
        for where, labels in by_machine.items()
    )


def gpu_values() -> dict[str, str]:
    """The GPU call's figures (gpu_h200/), and the two configs' sampling and update sizes."""
    from refpo_warp.algorithms.refpo import ReFPO
    from refpo_warp.models.flow_actor import FlowActor
    from refpo_warp.utils.options import option_fields

    script = (GPU / "run.sh").read_text()
    limits = dict(re.findall(r'"(\w+) (\d+)"', script))
    summary = dict(re.findall(r"^(\w+) rc=(\d+)", (GPU / "summary.txt").read_text(), re.MULTILINE))
    found = re.search(r"max_iterations=(\d+)", script)
    if found is None:
        raise DataFileError(f"{GPU / 'run.sh'}: no max_iterations=<n> (the iterations the GPU job requested)")
    requested = found.group(1)
    head = "| algo | iterations | env steps | training time | env steps / s (median iteration) | last training return |"
    table = [head, "|---|---|---|---|---|---|"]
    rate, cfg = {}, {}
    for algo in ("fpo_pp", "refpo"):
        rows = read_jsonl(GPU / f"{algo}_progress.jsonl")
        cfg[algo] = load_yaml(GPU / f"{algo}_config.yaml")
        last = rows[-1]
        rate[algo] = last["env_steps"] / last["time_s"]
        median = statistics.median(r["steps_per_s"] for r in rows)
        table.append(
            f"| `{algo}` | {len(rows)} ({rows[0]['iteration']}..{last['iteration']}) | {last['env_steps']:,} | "
            f"{last['time_s']:.0f} s | {rate[algo]:,.0f} ({median:,.0f}) | {last['reward_mean']:.0f} |"
        )
    actor_default = {f.name: f.default for f in dataclasses.fields(FlowActor.Options)}["num_flow_steps"]
    pairs_default = option_fields(ReFPO)["num_mc_samples"].default
    fp, rf = cfg["fpo_pp"], cfg["refpo"]
    n_fp = len([line for line in (GPU / "fpo_pp_progress.jsonl").read_text().splitlines() if line])
    gpu_name = (GPU / "gpu.txt").read_text().splitlines()[1].split(",")[0].strip()
    return {
        "gpu_name": gpu_name,
        "gpu_envs": f"{fp['num_envs']:,}",
        "gpu_steps": f"{fp['runner']['num_steps_per_env']:,}",
        "gpu_iteration_steps": f"{fp['num_envs'] * fp['runner']['num_steps_per_env']:,}",
        "gpu_requested": requested,
        "gpu_table": "\n".join(table),
        "gpu_rate_ratio": f"{rate['fpo_pp'] / rate['refpo']:.2f}",
        "gpu_fp_flow": str(fp["actor"].get("num_flow_steps", actor_default)),
        "gpu_rf_flow": str(rf["actor"].get("num_flow_steps", actor_default)),
        "gpu_fp_pairs": str(fp["algorithm"].get("num_mc_samples", pairs_default)),
        "gpu_rf_pairs": str(rf["algorithm"].get("num_mc_samples", pairs_default)),
        "gpu_fp_epochs": str(fp["algorithm"]["num_learning_epochs"]),
        "gpu_rf_epochs": str(rf["algorithm"]["num_learning_epochs"]),
        "gpu_limit": limits["fpo_pp"],
        "gpu_fp_rc": summary.get("fpo_pp", "?"),
        "gpu_fp_done": str(n_fp),
    }


def pairs_by_seed(a: dict[str, dict[int, float]], b: dict[str, dict[int, float]]):
    """(task, seed, a, b) for every (task, seed) both have."""
    return [(t, s, a[t][s], b[t][s]) for t in TASKS for s in sorted(set(a[t]) & set(b[t]))]


def findings(ms: dict[str, Method], data: dict) -> dict[str, str]:
    out = {}
    au = data[AUTHORS]
    # Against PPO, FPO and ReFPO, seed by seed.
    below = []
    for key in ("ppo", "fpo", "refpo"):
        pairs = pairs_by_seed(au["multi"], data[key]["multi"])
        n_below = sum(x < y for _, _, x, y in pairs)
        text = f"{ms[key].name}'s in {n_below} of {len(pairs)}"
        exceptions = [
            f"{short(t)} seed {s}, {ms[key].name} {num(y)} against FPO++ {num(x)}" for t, s, x, y in pairs if x >= y
        ]
        if exceptions:
            text += f" (not below: {'; '.join(exceptions)})"
        below.append(text)
    out["vs_others"] = ", ".join(below)
    means = {k: {t: np.mean(list(data[k]["multi"][t].values())) for t in TASKS if data[k]["multi"][t]} for k in data}
    out["authors_means"] = ", ".join(f"{num(means[AUTHORS][t])} on {short(t)}" for t in TASKS)
    out["authors_headline"] = ", ".join(
        num(np.mean(list(au["headline"][t].values()))) for t in TASKS if au["headline"][t]
    )
    for key in ("ppo", "refpo"):
        out[f"{key}_means"] = ", ".join(num(means[key][t]) for t in TASKS)
    pm = "dmc_point_mass"
    out["pm_seeds"] = " / ".join(num(au["multi"][pm][s]) for s in sorted(au["multi"][pm]))
    # ReFPO on FPO++ against FPO++.
    pairs = pairs_by_seed(data["refpo_pp"]["multi"], au["multi"])
    gap = max(pairs, key=lambda p: abs(p[2] - p[3]))
    out["reflow_max_gap"] = f"{abs(gap[2] - gap[3]):.1f}"
    out["reflow_gap_where"] = f"{short(gap[0])} seed {gap[1]}, ReFPO on FPO++ {num(gap[2])} against FPO++ {num(gap[3])}"
    out["reflow_pairs"] = str(len(pairs))
    # Zero noise against random noise, run by run; the headline N = 64 against N = 10, both from zero noise.
    zero, head = [], []
    for t in TASKS:
        p = [
            (s, au["multi_zero"][t][s], au["multi"][t][s])
            for s in sorted(set(au["multi_zero"][t]) & set(au["multi"][t]))
        ]
        zero.append(
            f"{short(t)} {num(np.mean([r for _, _, r in p]))} → {num(np.mean([z for _, z, _ in p]))}, higher in "
            f"{sum(z > r for _, z, r in p)} of {len(p)} runs"
        )
        h = [
            (s, au["headline"][t][s], au["multi_zero"][t][s])
            for s in sorted(set(au["headline"][t]) & set(au["multi_zero"][t]))
        ]
        head.append(
            f"{short(t)} {num(np.mean([a for _, a, _ in h]))} against {num(np.mean([b for _, _, b in h]))}, higher in "
            f"{sum(a > b for _, a, b in h)} of {len(h)} runs"
        )
    out["zero_noise"] = "; ".join(zero)
    out["headline_vs_ten"] = "; ".join(head)
    # The flow's straightness and the one-step share, from report/runs.csv.
    share = load_yaml(CRITERIA)["goal"]["one_step"]["share"]
    rows = [r for r in read_rows(REPORT) if r["status"] == "ok"]
    err = {}
    for label in (AUTHORS, "refpo_pp"):
        for t in TASKS:
            vals = [float(r["one_step"]) for r in rows if r["label"] == label and r["task"] == t and r["one_step"]]
            if vals:
                err[(label, t)] = float(np.mean(vals))
    out["one_step_low"] = f"{min(err.values()):.1e}"
    out["one_step_high"] = f"{max(err.values()):.1e}"
    out["share"] = str(share)
    held, counts = 0, []
    for t in TASKS:
        runs = [r for r in rows if r["label"] == AUTHORS and r["task"] == t]
        k = sum(float(r["return_1"]) >= share * float(r["return_multi"]) for r in runs)
        held += k
        counts.append(f"{short(t)} {k}/{len(runs)}")
    out["share_held"] = f"{held} of {sum(r['label'] == AUTHORS for r in rows)}"
    out["share_counts"] = ", ".join(counts)
    straight = [float(r["straightness"]) for r in rows if r["label"] in (AUTHORS, "refpo_pp") and r["straightness"]]
    out["straight_range"] = f"{min(straight):.2f} to {max(straight):.2f}"
    # Run health by FPO++'s rule.
    from refpo_warp.evaluation.run_health import MIN_PLATEAU, WINDOW

    health: dict[str, int] = {}
    for r in rows:
        health[r["health"]] = health.get(r["health"], 0) + 1
    out["health"] = ", ".join(f"{n} `{h}`" for h, n in sorted(health.items()))
    out["health_runs"] = str(len(rows))
    out["health_needs"] = str(MIN_PLATEAU + WINDOW)
    return out


def lr_text(data: dict, ms: dict[str, Method]) -> str:
    """FPO++ at learning rate 3e-4 against its own, on the tasks it ran."""
    key = "fpo_pp_lr3e-4"
    if key not in data:
        return "not run"
    lr, au, prof = data[key], data[AUTHORS], data.get("profile:fpo_pp")
    parts = []
    for t in TASKS:
        if not lr["multi"][t]:
            continue
        p = poi(lr["multi"], au["multi"], t)
        if p is None:  # no run at its own rate on t
            continue
        seeds = sorted(set(lr["multi"][t]) & set(au["multi"][t]))
        higher = sum(lr["multi"][t][s] > au["multi"][t][s] for s in seeds)
        text = (
            f"on {short(t)} its N = 10 return is {cell(lr['multi'][t])} against {cell(au['multi'][t])}, higher in "
            f"{higher} of {len(seeds)} seeds ({' / '.join(num(lr['multi'][t][s]) for s in seeds)} against "
            f"{' / '.join(num(au['multi'][t][s]) for s in seeds)}; P(improvement) "
            f"{p.text(2)}: {short_verdict(p, 'the higher rate', 'its own')})"
        )
        if lr["headline"][t] and au["headline"][t]:
            text += f", and its N = 64 zero-noise return {cell(lr['headline'][t])} against {cell(au['headline'][t])}"
        q = poi(prof["multi"], lr["multi"], t) if prof is not None else None
        if q is not None and prof is not None:
            text += (
                f"; the first grid's FPO++ reached {cell(prof['multi'][t])} at N = 10 (P(a first-grid run beats one at "
                f"the higher rate) {q.text(2)}: "
                f"{short_verdict(q, 'the first grid', 'the higher rate')})"
            )
        parts.append(text)
    return "; ".join(parts)


def clip_text(data: dict, ms: dict[str, Method]) -> str:
    present = [label for label in CLIP_LABELS if label in data and any(data[label]["multi"].values())]
    if not present:
        return (
            "Not run yet: `report/runs.csv` has no row of "
            + " or ".join(f"`{label}`" for label in CLIP_LABELS)
            + ". The rows and their comparison with the joint clip appear here when they do."
        )
    pm = "dmc_point_mass"
    means = ["| FPO++ at the authors' values, with | seeds | N = 10 | N = 64, zero noise |", "|---|---|---|---|"]
    for key, name in ((AUTHORS, "the joint clip"), *((label, ms[label].name) for label in present)):
        runs = data[key]
        seeds = set(runs["multi"][pm]) | set(runs["headline"][pm])
        means.append(f"| {name} | {seeds_text(seeds)} | {cell(runs['multi'][pm])} | {cell(runs['headline'][pm])} |")
    rows, _ = poi_rows([(label, AUTHORS, (ms[label].name, "the joint clip")) for label in present], ms, data)
    return "\n".join(means) + "\n\n" + poi_table(rows)
