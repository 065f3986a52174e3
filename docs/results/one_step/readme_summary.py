"""The top of one_step/README.md: cpu_dmc's standing, the summary, how it was measured, the main table and the
directions. Each section reads the page's data (readme_data.py) and what earlier sections added to it."""

import statistics
from types import SimpleNamespace

import numpy as np
import run_rows as st
from checkpoint_probes import TAUS
from intervention import VARIANTS
from readme_data import REFPO_VARIANTS, SHORT, diag, variant_roles
from run_rows import MULTI, ONE

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.phrases import and_list


def cpu_dmc_standing(c: SimpleNamespace) -> dict:
    """cpu_dmc's standing: where the 1-step return of its ReFPO runs collapses."""
    below, dmc, runs, tasks = c.below, c.dmc, c.runs, c.tasks
    out: dict = {}
    parts = []
    for task in tasks:
        m, o = runs("refpo", task, MULTI, dmc), runs("refpo", task, ONE, dmc)
        k = sum(st.collapsed(m[s], o[s], below) for s in m if s in o)
        text = f"{st.of(k, len(m))} seeds on {st.short(task)}"
        if k:
            gone = [s for s in m if s in o and st.collapsed(m[s], o[s], below)]
            text += f" (1-step {st.span([o[s] for s in gone], 1)} against 10-step {st.span([m[s] for s in gone], 0)})"
        parts.append(text)
    dmc_seeds = sorted({s for t in tasks for s in runs("refpo", t, MULTI, dmc)})
    out["cpu_dmc_standing"] = (
        f"in its ReFPO runs (seeds {seeds_text(dmc_seeds)}) the 1-step return collapses in " + and_list(parts)
    )
    return out


def in_short(c: SimpleNamespace) -> dict:
    """The page's summary: the paths, the probe, Straightness against the one-step error, the intervention, whole
    runs."""
    below, inter, lam, names, pm_task, probes, runs, seed, settle_window, tasks = (
        c.below,
        c.inter,
        c.lam,
        c.names,
        c.pm_task,
        c.probes,
        c.runs,
        c.seed,
        c.settle_window,
        c.tasks,
    )
    out: dict = {}
    paths = probes["refpo"]["paths"]
    n1, n10 = (np.array(paths[k]["position"]) for k in ("N=1", f"N={len(TAUS)}"))
    end1, end10 = np.linalg.norm(n1[-1], axis=-1), np.linalg.norm(n10[-1], axis=-1)
    moved = np.linalg.norm(n1[-1] - n1[-1 - settle_window], axis=-1).max()
    steps, envs = n1.shape[0] - 1, n1.shape[1]
    settles = moved < 0.1 * end1.min()
    spread_xy = n1[-1].max(axis=0) - n1[-1].min(axis=0)
    same_offset = spread_xy.max() < 0.25 * end1.mean()
    offset = (
        f", at about the same offset (x {st.span(n1[-1][:, 0], 3)}, y {st.span(n1[-1][:, 1], 3)}; the target at "
        "the origin)"
        if same_offset
        else ""
    )
    out["short_paths"] = (
        (
            "The 1-step policy does not wander: it settles at a point displaced from the target, where the 10-step "
            "policy settles on it."
            if settles and end1.min() > 3 * end10.max()
            else "The 1-step and 10-step policies end at different distances from the target."
        )
        + f" In seed {seed}'s paths from {envs} shared starts (ReFPO, independent pairs), after {steps} steps the "
        f"1-step point masses all sit {st.span(end1, 3)} from the target{offset}, none having moved more than "
        f"{moved:.4f} over the last {settle_window} steps; the 10-step ones end {st.span(end10, 3)} from it."
    )
    refpo_probe = probes["refpo"]
    its = refpo_probe["iterations"]
    err_n = refpo_probe["states_N"]["one_step_error"]
    spread_n = refpo_probe["states_N"]["policy_spread"]
    own = refpo_probe["by_tau"]["own_path"]
    taus = refpo_probe["by_tau"]["tau"]
    low_at = int(np.argmin(own))
    out["short_probe"] = (
        f"Its one-step error grows over training as the policy narrows (seed {seed}'s probe: "
        f"{diag(err_n[0])} at iteration {its[0]}, {diag(err_n[len(its) // 2])} at {its[len(its) // 2]}, "
        f"{diag(err_n[-1])} at {its[-1]}, while the spread of a_N falls from {spread_n[0]:.2f} to {spread_n[-1]:.2f}), "
        f"and the sampler's velocity error along its own paths at τ = 0, where one Euler step reads the field, is "
        f"{own[0] / own[low_at]:.1f}× its lowest over flow times ({own[0]:.2f} against {own[low_at]:.2f} at "
        f"τ = {taus[low_at]:g})."
    )
    s_pm = {lb: statistics.fmean(runs(lb, pm_task, "straightness").values()) for lb in REFPO_VARIANTS}
    e_pm = {lb: statistics.fmean(runs(lb, pm_task, "one_step").values()) for lb in REFPO_VARIANTS}
    o_pm = {lb: statistics.fmean(runs(lb, pm_task, ONE).values()) for lb in REFPO_VARIANTS}
    others = [lb for lb in REFPO_VARIANTS if lb != "refpo"]
    if min(s_pm, key=s_pm.__getitem__) == "refpo" and max(e_pm, key=e_pm.__getitem__) == "refpo":
        verdict = (
            "The paper's Straightness Error (the CFM residual on independent pairs) does not see this: on point_mass "
            f"it ranks independent pairs the straightest of the ReFPO variants ({s_pm['refpo']:.2f} against "
            f"{' and '.join(f'{s_pm[lb]:.2f}' for lb in others)}) while the one-step error (eval) ranks them the "
            f"farthest from one-step ({e_pm['refpo']:.2f} against {' and '.join(f'{e_pm[lb]:.2f}' for lb in others)})"
        )
        verdict += ", and they have the lowest 1-step return." if min(o_pm, key=o_pm.__getitem__) == "refpo" else "."
    else:
        verdict = (
            "On point_mass, Straightness (eval) "
            + ", ".join(f"{names[lb]} {s_pm[lb]:.2f}" for lb in REFPO_VARIANTS)
            + "; one-step error "
            + ", ".join(f"{e_pm[lb]:.2f}" for lb in REFPO_VARIANTS)
            + "."
        )
    out["short_straightness"] = verdict

    variants, start = inter["variants"], inter["checkpoint"]
    role = variant_roles(variants)

    def e(name, where="states_N"):
        return (start if name == "checkpoint" else variants[name])[where]["one_step_error"]

    def coef_of(name):
        return VARIANTS[name].get("algorithm.reflow_coef", lam("refpo")["mean"])

    k, it = inter["iterations"], inter["iteration"]
    base, none = e(role["base"]), e(role["no_reflow"])
    alike = abs(base - none) < 0.05 * none
    out["short_intervention"] = (
        f"In {k} iterations from the iteration-{it} checkpoint of seed {seed} (one-step error {e('checkpoint'):.2f}), "
        f"the negative-advantage half of the surrogate alone "
        f"{'raises' if e(role['negative']) > e('checkpoint') else 'lowers'} the error to {e(role['negative']):.2f} "
        f"and the positive half alone {'lowers' if e(role['positive']) < e('checkpoint') else 'raises'} it to "
        f"{e(role['positive']):.2f}; the paper's independent Reflow term at λ = {coef_of(role['base']):g} "
        + (
            f"changes nothing measurable ({base:.3f} with it, {none:.3f} without)"
            if alike
            else f"moves it ({base:.3f} with it, {none:.3f} without)"
        )
        + (
            f", and coupled pairs cut it ({e(role['coupled']):.3f} at λ = {coef_of(role['coupled']):g}, "
            f"{e(role['coupled_high']):.3f} at λ = {coef_of(role['coupled_high']):g})."
            if e(role["coupled"]) < none and e(role["coupled_high"]) < none
            else f"; coupled pairs leave {e(role['coupled']):.3f} and {e(role['coupled_high']):.3f}."
        )
    )

    # Whole runs on point_mass.
    pm_multi = {lb: runs(lb, pm_task, MULTI) for lb in REFPO_VARIANTS}
    pm_one = {lb: runs(lb, pm_task, ONE) for lb in REFPO_VARIANTS}
    held = {lb: [s for s in pm_multi[lb] if not st.collapsed(pm_multi[lb][s], pm_one[lb][s], below)] for lb in pm_multi}
    est = st.intervals({f"{lb}:{t}": list(runs(lb, t, MULTI).values()) for lb in REFPO_VARIANTS for t in tasks})

    def iv(lb, t=pm_task):
        return st.interval_text(est[f"{lb}:{t}"])

    def held_text(lb):
        kept, lost = held[lb], [s for s in pm_one[lb] if s not in held[lb]]
        if not kept:
            return f"0 of {len(pm_one[lb])} seeds (1-step {st.pm(pm_one[lb].values())})"
        return (
            f"{st.of(len(kept), len(pm_one[lb]))} seeds (1-step {' and '.join(f'{pm_one[lb][s]:.0f}' for s in kept)}"
            + (
                f"; the other{'s' if len(lost) > 1 else ''} {', '.join(f'{pm_one[lb][s]:.1f}' for s in lost)})"
                if lost
                else ")"
            )
        )

    apart = [lb for lb in others if st.separated(est[f"{lb}:{pm_task}"], est[f"refpo:{pm_task}"])]
    run_seeds = sorted({s for lb in REFPO_VARIANTS for s in pm_multi[lb]})
    out["short_runs"] = (
        f"Over whole runs (seeds {seeds_text(run_seeds)}), **coupled pairs at λ = {lam('refpo_coupled')['mean']:g} "
        f"remove the collapse in {held_text('refpo_coupled')}, and the adaptive λ in {held_text('refpo_adaptive')}**, "
        + (
            "with 10-step returns these seeds do not separate from ReFPO's"
            if not apart
            else f"with 10-step returns apart from ReFPO's for {and_list([names[lb] for lb in apart])}"
        )
        + f" ({iv('refpo_coupled')} and {iv('refpo_adaptive')} against {iv('refpo')}). "
        + (
            "Neither is an answer yet."
            if any(len(held[lb]) < len(pm_one[lb]) for lb in others)
            else "Both hold the 1-step return in every seed."
        )
    )
    vars(c).update(
        apart=apart,
        base=base,
        coef_of=coef_of,
        e=e,
        envs=envs,
        err_n=err_n,
        est=est,
        held=held,
        it=it,
        its=its,
        iv=iv,
        k=k,
        low_at=low_at,
        none=none,
        others=others,
        own=own,
        paths=paths,
        pm_one=pm_one,
        refpo_probe=refpo_probe,
        role=role,
        s_pm=s_pm,
        spread_n=spread_n,
        start=start,
        steps=steps,
        taus=taus,
        variants=variants,
    )
    return out


def how_measured(c: SimpleNamespace) -> dict:
    """How it was measured: the runs, the checkpoints, the env steps, the runs that reproduce cpu_dmc's."""
    dmc, it, its, k, pm_task, rows, runs, spec, tasks, training = (
        c.dmc,
        c.it,
        c.its,
        c.k,
        c.pm_task,
        c.rows,
        c.runs,
        c.spec,
        c.tasks,
        c.training,
    )
    out: dict = {}
    out["n_main_runs"] = sum(1 for r in rows if r["label"] in REFPO_VARIANTS)
    out["n_fpo_runs"] = sum(1 for r in rows if r["label"] == "fpo")
    save = spec["overrides"]["runner.save_interval"]
    out["save_interval"] = save
    out["every"] = (its[1] - its[0]) // save
    out["intervene"], out["intervene_iterations"] = it, k
    last_steps: dict[int, list[str]] = {}
    for task in tasks:
        last_steps.setdefault(training[task]["refpo"]["eval/return_N10"]["env_steps"], []).append(st.short(task))
    out["env_steps"] = ", ".join(
        (f"{n / 1e6:.2f}M" if n >= 1e6 else f"{n / 1e3:.0f}k")
        + (" env steps" if i == 0 else "")
        + f" for {' and '.join(ts)}"
        for i, (n, ts) in enumerate(sorted(last_steps.items()))
    )
    checked = same = 0
    for r in rows:
        if r["label"] not in ("refpo", "fpo"):
            continue
        twin = [d for d in dmc if (d["task"], d["label"], d["seed"]) == (r["task"], r["label"], r["seed"])]
        if twin:
            checked += 1
            same += all(r[key] == twin[0][key] for key in (MULTI, ONE, "straightness", "explosion"))
    rm, ro = runs("refpo", pm_task, MULTI), runs("refpo", pm_task, ONE)
    out["reproduce"] = (
        f"The runs of ReFPO with independent pairs and of FPO equal the `cpu_dmc` runs of the same seeds to the last "
        f"digit in {st.of(same, checked)} (final 10-step and 1-step returns, Straightness, Explosion; point_mass ReFPO "
        f"{statistics.fmean(rm.values()):.2f} / {statistics.fmean(ro.values()):.2f} on average): the one-step "
        "diagnostic these runs log draws its noise from its own generator and leaves training as it was."
        if checked and same == checked
        else f"The runs of ReFPO with independent pairs and of FPO equal the `cpu_dmc` runs of the same seeds in "
        f"{st.of(same, checked)}."
    )
    vars(c).update(checked=checked, rm=rm, ro=ro, same=same)
    return out


def main_table(c: SimpleNamespace) -> dict:
    """The main table: every method's final returns and diagnostics per task."""
    dmc, names, rows, runs, tasks = c.dmc, c.names, c.rows, c.runs, c.tasks
    out: dict = {}
    header = (
        "| task | method | runs | 10-step | 1-step | Straightness | Explosion | one-step error (eval) | "
        "one-step ratio (eval) |"
    )
    lines = [header, "|---|" + "---|" * 8]
    for task in tasks:
        entries = [("ppo", dmc, "PPO (cpu_dmc)")]
        fpo_here = runs("fpo", task, MULTI)
        entries.append(("fpo", rows, "FPO") if fpo_here else ("fpo", dmc, "FPO (cpu_dmc)"))
        entries += [(lb, rows, names[lb]) for lb in REFPO_VARIANTS]
        for lb, source, label in entries:
            m = runs(lb, task, MULTI, source)
            if not m:
                continue

            def mean_of(key, fmt, lb=lb, source=source, task=task):
                v = runs(lb, task, key, source)
                return fmt(statistics.fmean(v.values())) if v else "--"

            lines.append(
                f"| {st.short(task)} | {label} | {len(m)} | {st.pm(m.values())} | "
                + (st.pm(runs(lb, task, ONE, source).values()) if runs(lb, task, ONE, source) else "--")
                + f" | {mean_of('straightness', lambda x: f'{x:.2f}')} | {mean_of('explosion', lambda x: f'{x:.2g}')}"
                + f" | {mean_of('one_step', lambda x: f'{x:.3f}')}"
                + f" | {mean_of('one_step_ratio', lambda x: f'{x:.2f}')} |"
            )
    out["main_table"] = "\n".join(lines)
    out["table_seeds"] = seeds_text({int(r["seed"]) for r in rows})
    return out


def directions(c: SimpleNamespace) -> dict:
    """The directions: coupled pairs and the adaptive λ against independent pairs."""
    apart, est, held, iv, others, pm_one, runs, tasks = (
        c.apart,
        c.est,
        c.held,
        c.iv,
        c.others,
        c.pm_one,
        c.runs,
        c.tasks,
    )
    out: dict = {}
    bullets = []
    coupled_one = pm_one["refpo_coupled"]
    bullets.append(
        "- **Coupled pairs remove the point_mass collapse: "
        + ("no" if not held["refpo_coupled"] else f"in {st.of(len(held['refpo_coupled']), len(coupled_one))} seeds")
        + "** "
        f"(1-step {', '.join(f'{v:.1f}' for v in coupled_one.values())}), at a 10-step return of {iv('refpo_coupled')} "
        f"against ReFPO's {iv('refpo')} ("
        + ("apart" if "refpo_coupled" in apart else "the intervals overlap")
        + f"). **The adaptive λ: in {st.of(len(held['refpo_adaptive']), len(pm_one['refpo_adaptive']))} seeds** "
        f"(1-step {', '.join(f'{v:.1f}' for v in pm_one['refpo_adaptive'].values())}), at a 10-step return of "
        f"{iv('refpo_adaptive')} ("
        + ("apart from ReFPO's" if "refpo_adaptive" in apart else "overlapping ReFPO's")
        + ")."
    )
    one_step_eval = {(lb, t): runs(lb, t, "one_step") for lb in REFPO_VARIANTS for t in tasks}
    lower_tasks = [
        t
        for t in tasks
        if all(
            statistics.fmean(one_step_eval[(lb, t)].values()) < statistics.fmean(one_step_eval[("refpo", t)].values())
            for lb in others
        )
    ]
    pairs = lower = 0
    for t in tasks:
        for lb in others:
            for s, v in one_step_eval[(lb, t)].items():
                if s in one_step_eval[("refpo", t)]:
                    pairs += 1
                    lower += v < one_step_eval[("refpo", t)][s]
    bullets.append(
        "- **Lower one-step error (eval) than independent pairs: "
        + (
            "holds for both on every task"
            if len(lower_tasks) == len(tasks)
            else f"on {st.of(len(lower_tasks), len(tasks))} tasks"
        )
        + f"** on the means, and in {st.of(lower, pairs)} (variant, task, seed) pairs seed by seed ("
        + ", ".join(
            f"{st.short(t)} {' and '.join(diag(statistics.fmean(one_step_eval[(lb, t)].values())) for lb in others)} "
            f"against {diag(statistics.fmean(one_step_eval[('refpo', t)].values()))}"
            for t in tasks
        )
        + ")."
    )
    s_mean = {(lb, t): statistics.fmean(runs(lb, t, "straightness").values()) for lb in REFPO_VARIANTS for t in tasks}
    higher = all(s_mean[(lb, t)] > s_mean[("refpo", t)] for lb in others for t in tasks)
    bullets.append(
        "- **The paper's Straightness Error "
        + ("moves the other way**: higher for both on every task" if higher else "does not move with it**: mixed")
        + f" ({st.span([s_mean[(lb, t)] for lb in others for t in tasks])} against "
        f"{st.span([s_mean[('refpo', t)] for t in tasks])}); our reading: neither trains the marginal flow as much as "
        "independent pairs do. The two measures disagree."
    )
    expl = {(lb, t): statistics.fmean(runs(lb, t, "explosion").values()) for lb in REFPO_VARIANTS for t in tasks}
    fpo_expl = [
        (t, statistics.fmean(runs("fpo", t, "explosion").values())) for t in tasks if runs("fpo", t, "explosion")
    ]
    bullets.append(
        f"- **Explosion Rate**: at most {max(expl.values()):.2g} for every ReFPO variant on every task (FPO: "
        + ", ".join(f"{x:.2g} on {st.short(t)}" for t, x in fpo_expl)
        + ")."
    )
    cp, re_ = "dmc_cartpole_balance", "dmc_reacher_easy"
    cp_multi = runs("refpo", cp, MULTI)
    weakest = min(cp_multi, key=cp_multi.__getitem__)
    cp_up = all(est[f"{lb}:{cp}"].point > est[f"refpo:{cp}"].point for lb in others)
    cp_one_kept = all(
        statistics.fmean(runs(lb, cp, ONE).values()) >= 0.9 * statistics.fmean(runs("refpo", cp, ONE).values())
        for lb in others
    )
    re_ref = runs("refpo", re_, MULTI)
    re_below = {lb: [s for s, v in runs(lb, re_, MULTI).items() if s in re_ref and v < re_ref[s]] for lb in others}
    re_above = {lb: [s for s, v in runs(lb, re_, MULTI).items() if s in re_ref and v > re_ref[s]] for lb in others}
    re_down = all(est[f"{lb}:{re_}"].point < est[f"refpo:{re_}"].point for lb in others)
    bullets.append(
        f"- **cartpole_balance: both extensions' 10-step means are {'higher' if cp_up else 'not both higher'}** "
        f"({iv('refpo_coupled', cp)} and {iv('refpo_adaptive', cp)} against {iv('refpo', cp)}; ReFPO's seed {weakest}, "
        f"{cp_multi[weakest]:.1f}, is the low one"
        + (
            "; the intervals overlap"
            if not any(st.separated(est[f"{lb}:{cp}"], est[f"refpo:{cp}"]) for lb in others)
            else ""
        )
        + ")"
        + (" and keep its 1-step return" if cp_one_kept else "")
        + f"; **reacher_easy: both are {'lower' if re_down else 'not both lower'} on average** "
        f"({iv('refpo_coupled', re_)} and {iv('refpo_adaptive', re_)} against {iv('refpo', re_)}"
        + (
            "; the intervals overlap"
            if not any(st.separated(est[f"{lb}:{re_}"], est[f"refpo:{re_}"]) for lb in others)
            else ""
        )
        + "), "
        + "; ".join(
            f"{SHORT[lb]} below independent pairs in seed{'s' if len(re_below[lb]) != 1 else ''} "
            f"{and_list([str(s) for s in re_below[lb]]) if re_below[lb] else 'none'}"
            + (
                f" and above it in seed{'s' if len(re_above[lb]) != 1 else ''} "
                f"{and_list([str(s) for s in re_above[lb]])}"
                if re_above[lb]
                else ""
            )
            for lb in others
        )
        + "."
    )
    out["directions"] = "\n".join(bullets)
    vars(c).update(cp=cp, cp_multi=cp_multi, re_=re_, re_below=re_below, re_ref=re_ref, weakest=weakest)
    return out
