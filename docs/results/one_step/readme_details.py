"""The rest of one_step/README.md: over training, the paths, the probes, the velocity error by flow time, the
intervention, the mechanism, the other tasks, the diagnostics and leads. Each section reads the page's data
(readme_data.py) and what earlier sections added to it."""

import statistics
from types import SimpleNamespace

import numpy as np
import run_rows as st
import yaml
from checkpoint_probes import PROBE_KEYS, TAUS
from intervention import VARIANTS
from readme_data import PAGE_METHODS, REFPO_VARIANTS, SHORT, diag
from run_rows import MULTI, ONE

from refpo_warp.studies.reports.phrases import and_list


def over_training(c: SimpleNamespace) -> dict:
    """Over training: the last update's table and the one-step error and λ of FPO, ReFPO and the adaptive λ."""
    lam, names, pm_task, tasks, training = c.lam, c.names, c.pm_task, c.tasks, c.training
    out: dict = {}
    table = [
        "| task | method | N = 1 return | one-step error | one-step ratio | λ |",
        "|---|---|---|---|---|---|",
    ]

    def rng(v, f):
        return f"{f(v['mean'])} [{f(v['low'])}, {f(v['high'])}]"

    def ratio_fmt(x):
        return f"{x:.0f}" if abs(x) >= 100 else f"{x:.2f}"

    for task in tasks:
        for lb in PAGE_METHODS:
            if lb not in training[task]:
                continue
            t = training[task][lb]
            table.append(
                f"| {st.short(task)} | {names[lb]} | {rng(t['eval/return_N1'], lambda x: f'{x:.0f}')} | "
                f"{rng(t['Flow/one_step_error'], diag)} | {rng(t['Flow/one_step_ratio'], ratio_fmt)} | "
                f"{rng(t['Flow/reflow_coef'], lambda x: f'{x:.2g}')} |"
            )
    out["last_update_table"] = "\n".join(table)
    tr = training[pm_task]
    fpo_err, ref_err = tr["fpo"]["Flow/one_step_error"], tr["refpo"]["Flow/one_step_error"]
    ad_lam = {task: training[task]["refpo_adaptive"]["Flow/reflow_coef"] for task in tasks}
    fixed: dict[float, list[str]] = {}
    for t in tasks:
        if ad_lam[t]["low"] == ad_lam[t]["high"]:
            fixed.setdefault(ad_lam[t]["mean"], []).append(st.short(t))
    spread_out = [t for t in tasks if ad_lam[t]["low"] != ad_lam[t]["high"]]
    text = (
        f"On point_mass, FPO's one-step error (λ = 0) ends at {diag(fpo_err['mean'])} and ReFPO's at "
        f"{diag(ref_err['mean'])} (λ = {lam('refpo')['mean']:g}): "
        + (
            "the independent term leaves it about where FPO has it (the ranges overlap). "
            if fpo_err["high"] >= ref_err["low"] and ref_err["high"] >= fpo_err["low"]
            else "the ranges are apart. "
        )
    )
    text += (
        "The adaptive λ ends at "
        + and_list([f"{value:g} in every seed on {and_list(ts)}" for value, ts in fixed.items()])
        if fixed
        else "The adaptive λ ends"
    )
    text += "".join(
        f"; on {st.short(t)} between {ad_lam[t]['low']:g} and {ad_lam[t]['high']:g} across seeds (mean "
        f"{ad_lam[t]['mean']:.2g})"
        for t in spread_out
    )
    text += (
        ". In the figures it first falls to its floor (the ratio is small early) and climbs once the ratio passes the "
        "top of its band. When each seed's 1-step return fell, and what the ratio and λ were then, is recorded only "
        "in the runs' `progress.jsonl`, which is not committed, so this page does not time the collapse against the "
        "ratio."
    )
    out["over_training"] = text
    vars(c).update(ad_lam=ad_lam)
    return out


def paths_text(c: SimpleNamespace) -> dict:
    """The paths the 1-step and 10-step policies drive on point_mass."""
    alike_within, envs, paths, pm_task, probes, runs, steps, tasks = (
        c.alike_within,
        c.envs,
        c.paths,
        c.pm_task,
        c.probes,
        c.runs,
        c.steps,
        c.tasks,
    )
    out: dict = {}
    lines = []
    for lb in ("refpo", "refpo_coupled", "refpo_adaptive", "fpo"):
        p = probes[lb]["paths"]
        d1, d10 = (np.array(p[key]["distance"])[-1].mean() for key in ("N=1", f"N={len(TAUS)}"))
        r1, r10 = (f"{r:.1f}" if r < 100 else f"{r:.0f}" for r in (p["N=1"]["return"], p[f"N={len(TAUS)}"]["return"]))
        lines.append(f"{SHORT[lb]} {d1:.3f} / {d10:.3f} ({r1} / {r10})")
    cost = {
        t: (
            statistics.fmean(runs("refpo", t, "one_step").values()),
            statistics.fmean(runs("refpo", t, ONE).values()),
            statistics.fmean(runs("refpo", t, MULTI).values()),
        )
        for t in tasks
    }
    rest = [t for t in tasks if t != pm_task]
    out["path_envs"] = envs
    m1, m10 = (np.array(paths[key]["distance"]).mean(axis=1) for key in ("N=1", f"N={len(TAUS)}"))
    apart_at = next((i for i in range(len(m1)) if abs(m1[i] - m10[i]) > alike_within * m10[i]), len(m1) - 1)
    out["paths"] = (
        "for ReFPO with independent pairs, the mean distance to the target of the 1-step and 10-step masses falls "
        f"alike (within {100 * alike_within:g} %) for the first {apart_at} steps ({m1[0]:.2f} at the start, "
        f"{m1[apart_at]:.3f} and {m10[apart_at]:.3f} then); the 1-step one then levels off ({m1[-1]:.3f} at step "
        f"{steps}) while the 10-step one keeps falling ({m10[-1]:.3f}). After {steps} steps the mean distance at "
        "N = 1 / N = 10 (and the mean return over those steps) is "
        + "; ".join(lines)
        + ". A bias of a few hundredths in where the 1-step dynamics come to rest is worth "
        "nearly the whole return on this task, which is why the return is far more sensitive than a mean-squared "
        f"action error suggests; on {and_list([st.short(t) for t in rest])}, ReFPO's one-step error (eval) of "
        f"{' and '.join(diag(cost[t][0]) for t in rest)}, against point_mass's {diag(cost[pm_task][0])}, goes with "
        "1-step "
        f"returns of {' and '.join(f'{cost[t][1]:.0f}' for t in rest)} against 10-step ones of "
        f"{' and '.join(f'{cost[t][2]:.0f}' for t in rest)}."
    )
    return out


def probe_texts(c: SimpleNamespace) -> dict:
    """The sampler probe over checkpoints, and FPO as the contrast."""
    its, paths, pm_task, probes, refpo_probe, runs, seed, spread_n = (
        c.its,
        c.paths,
        c.pm_task,
        c.probes,
        c.refpo_probe,
        c.runs,
        c.seed,
        c.spread_n,
    )
    out: dict = {}
    out["probe_iterations"] = ", ".join(str(i) for i in its)
    out["last_iteration"] = its[-1]
    last_n = {key: refpo_probe["states_N"][key][-1] for key in PROBE_KEYS}
    last_1 = refpo_probe["states_1"]["one_step_error"][-1]
    close = 0.7 <= last_1 / last_n["one_step_error"] <= 1.4
    out["probe_text"] = (
        f"At the last checkpoint, for ReFPO with independent pairs, the one-step error on the 1-step policy's own "
        f"states is {last_1:.2f} against {last_n['one_step_error']:.2f} on the 10-step policy's"
        + (": the collapse is not a shift to states the field never saw. " if close else ". ")
        + f"a₁ is not the policy's mean action either: its distance to the mean of a_N (|a₁(ε) − mean a_N|², "
        f"{last_n['mean_gap']:.2f}) is {'larger than' if last_n['mean_gap'] > last_n['policy_spread'] else 'within'} "
        f"the policy's spread ({last_n['policy_spread']:.2f}), and a₁ still varies with ε "
        f"({last_n['one_step_spread']:.2f} over ε, against a_N's {last_n['policy_spread']:.2f}); our reading: the "
        "surrogate, not the Reflow term, decides where the 1-step sample goes (the independent term's minimiser "
        "would put a₁ on the mean action)."
    )
    fp = probes["fpo"]
    f_err, r_err = fp["states_N"]["one_step_error"], refpo_probe["states_N"]["one_step_error"]
    small = [i for i, (a, b) in enumerate(zip(f_err, r_err)) if b > 0 and a < 0.1 * b and fp["iterations"][i] > 0]
    through = fp["iterations"][small[-1]] if small else None
    f_spread = fp["states_N"]["policy_spread"]
    f_own = fp["by_tau"]["own_path"]
    f_paths = fp["paths"]
    fd1, fd10 = (np.array(f_paths[key]["distance"])[-1].mean() for key in ("N=1", f"N={len(TAUS)}"))
    fm, fo = runs("fpo", pm_task, MULTI), runs("fpo", pm_task, ONE)
    out["fpo_text"] = (
        "FPO (λ = 0) is the contrast: "
        + (
            f"its one-step error stays below a tenth of ReFPO's through iteration {through} "
            f"({diag(f_err[small[-1]])} against {diag(r_err[small[-1]])}) and rises late ({diag(f_err[-1])} at "
            f"{its[-1]}), "
            if through is not None
            else f"its one-step error ends at {diag(f_err[-1])}, "
        )
        + f"its policy narrows less (spread {f_spread[0]:.2f} → {f_spread[-1]:.2f}, against "
        f"{spread_n[0]:.2f} → {spread_n[-1]:.2f} for ReFPO), and its field is far from straight on its own paths "
        f"(velocity error {st.span(f_own, 1)} by τ). In seed {seed} its final returns are {fm[seed]:.0f} at N = 10 and "
        f"{fo[seed]:.1f} at N = 1, and its paths end {fd10:.3f} (N = 10) and {fd1:.3f} (N = 1) from the target on "
        f"average, against {np.array(paths[f'N={len(TAUS)}']['distance'])[-1].mean():.3f} for ReFPO's 10-step policy."
    )
    vars(c).update(close=close)
    return out


def by_tau_text(c: SimpleNamespace) -> dict:
    """The velocity error by flow time, on the sampler's own paths and on independent pairs."""
    err_n, its, low_at, names, own, pm_task, probes, refpo_probe, runs, seed, small_tau_below, taus = (
        c.err_n,
        c.its,
        c.low_at,
        c.names,
        c.own,
        c.pm_task,
        c.probes,
        c.refpo_probe,
        c.runs,
        c.seed,
        c.small_tau_below,
        c.taus,
    )
    out: dict = {}
    head = "| method | pairs | " + " | ".join(f"τ = {t:g}" for t in taus) + " |"
    table = [head, "|---|---|" + "---|" * len(taus)]
    for lb in PAGE_METHODS:
        bt = probes[lb]["by_tau"]
        for key, what in (("own_path", "own path"), ("independent", "independent")):
            table.append(f"| {names[lb]} | {what} | " + " | ".join(f"{v:.2f}" for v in bt[key]) + " |")
    out["tau_table"] = "\n".join(table)
    small_tau = [v for t, v in zip(taus, own) if t < small_tau_below]
    indep = refpo_probe["by_tau"]["independent"]
    coupled_own = probes["refpo_coupled"]["by_tau"]["own_path"]
    s_ref = runs("refpo", pm_task, "straightness")
    nonzero = [i for i, v in enumerate(err_n) if v > 0.01]
    first = nonzero[0] if nonzero else 0
    out["tau_text"] = (
        f"On its own paths, ReFPO's field (independent pairs) errs {st.span(small_tau)} at τ below "
        f"{small_tau_below:g}, "
        f"against {own[low_at]:.2f} at τ = {taus[low_at]:g}; one Euler step uses v(ε, 0) alone, ten steps average it "
        f"with the later ones. On independent pairs the error is {st.span(indep)} at every τ: the variance of the "
        "conditional target, which no field can remove, so the paper's Straightness ends at "
        f"{st.span(s_ref.values())} in ReFPO's point_mass runs while seed {seed}'s one-step error rises from "
        f"{diag(err_n[first])} at iteration {its[first]} to {diag(err_n[-1])} at {its[-1]}. With coupled pairs the "
        f"own-path error at τ = 0, the one a single Euler step reads, is {coupled_own[0]:.2f} against "
        "independent pairs' "
        f"{own[0]:.2f}."
    )
    vars(c).update(coupled_own=coupled_own)
    return out


def intervention_texts(c: SimpleNamespace) -> dict:
    """The intervention's checkpoint and its table."""
    below, start, variants = c.below, c.start, c.variants
    out: dict = {}
    ret = start["returns"]
    out["checkpoint_text"] = (
        ("before the collapse: " if not st.collapsed(ret["N=10"], ret["N=1"], below) else "")
        + f"one-step error {start['states_N']['one_step_error']:.3f} on the 10-step policy's states, "
        f"{start['own_path_by_tau'][0]:.2f} own-path velocity error at τ = 0, N = 10 / N = 1 returns "
        f"{ret['N=10']:.0f} / {ret['N=1']:.0f}"
    )
    table = [
        (
            "| change | one-step error after (10-step states / 1-step states) | own-path velocity error at τ = 0 | "
            "N = 10 / N = 1 return after |"
        ),
        "|---|---|---|---|",
        (
            f"| checkpoint (before) | {start['states_N']['one_step_error']:.3f} / "
            f"{start['states_1']['one_step_error']:.3f} | {start['own_path_by_tau'][0]:.2f} | "
            f"{ret['N=10']:.0f} / {ret['N=1']:.0f} |"
        ),
    ]
    for name in VARIANTS:
        v = variants[name]
        table.append(
            f"| {name} | {v['states_N']['one_step_error']:.3f} / {v['states_1']['one_step_error']:.3f} | "
            f"{v['own_path_by_tau'][0]:.2f} | {v['returns']['N=10']:.0f} / {v['returns']['N=1']:.0f} |"
        )
    out["intervention_table"] = "\n".join(table)
    return out


def mechanism(c: SimpleNamespace) -> dict:
    """The mechanism: what the surrogate's halves and the Reflow terms do to the one-step error."""
    (
        base,
        checked,
        close,
        coef_of,
        coupled_own,
        e,
        held,
        k,
        lam,
        none,
        pm_one,
        refpo_probe,
        role,
        same,
        seed,
        start,
        variants,
    ) = (
        c.base,
        c.checked,
        c.close,
        c.coef_of,
        c.coupled_own,
        c.e,
        c.held,
        c.k,
        c.lam,
        c.none,
        c.pm_one,
        c.refpo_probe,
        c.role,
        c.same,
        c.seed,
        c.start,
        c.variants,
    )
    out: dict = {}
    neg, pos = variants[role["negative"]], variants[role["positive"]]
    tau0 = start["own_path_by_tau"][0]
    pos_lowers = pos["states_N"]["one_step_error"] < e("checkpoint") and pos["own_path_by_tau"][0] < tau0
    bullets = [
        (
            "- **The surrogate's negative-advantage terms push the field away from the sampler's paths, its positive "
            f"terms pull it back.** Alone, the negative half multiplies the one-step error by "
            f"{neg['states_N']['one_step_error'] / e('checkpoint'):.1f} and the velocity error at τ = 0 by "
            f"{neg['own_path_by_tau'][0] / tau0:.0f} in {k} iterations; the positive half alone (a weighted CFM on the "
            f"policy's own actions) {'lowers both' if pos_lowers else 'does not lower both'} "
            f"({pos['states_N']['one_step_error']:.3f} and {pos['own_path_by_tau'][0]:.2f}). With both halves and no "
            f"Reflow term the error goes from {e('checkpoint'):.3f} to {none:.3f}: our reading is that they "
            "nearly cancel "
            "and what is left grows the error slowly as the policy narrows. The candidate mechanism, supported at this "
            "checkpoint."
        ),
        (
            "- **The paper's independent Reflow term does not hold the one-step sampler here.** Its minimiser "
            "makes one "
            f"Euler step land on the policy's mean action (`docs/algorithms.md`); at λ = {coef_of(role['base']):g} it "
            f"changes the one-step error by {abs(base - none):.3f} in {k} iterations against no Reflow term, at "
            f"λ = {coef_of(role['high']):g} by {abs(e(role['high']) - none):.3f}. Over whole runs the "
            "adaptive λ, which "
            f"ends at {lam('refpo_adaptive')['mean']:g} on point_mass, holds the 1-step return in "
            f"{st.of(len(held['refpo_adaptive']), len(pm_one['refpo_adaptive']))} seeds: a slower, indirect "
            "effect that "
            "this intervention does not isolate."
        ),
        (
            f"- **Coupled pairs act on the right quantity** ({none / e(role['coupled_high']):.1f}× lower error than no "
            f"Reflow term in {k} iterations at λ = {coef_of(role['coupled_high']):g}, "
            f"{none / e(role['coupled']):.1f}× at {coef_of(role['coupled']):g}) but, at λ = "
            f"{coef_of(role['coupled']):g} over a whole run, not strongly enough where it matters: seed {seed}'s last "
            f"checkpoint still has an own-path error of {coupled_own[0]:.2f} at τ = 0, and the collapse comes in "
            f"{st.of(len(pm_one['refpo_coupled']) - len(held['refpo_coupled']), len(pm_one['refpo_coupled']))} seeds."
        ),
    ]
    sat_n = refpo_probe["states_N"]["saturated_n"]
    sat_1 = refpo_probe["states_N"]["saturated_1"]
    init = sat_n[0]
    no_saturation = max(sat_n + sat_1) <= 1.15 * init
    bullets.append(
        "- **It is not a defect of the project** that we could find: the stored ε₀ reproduces every rollout action "
        "(`tests/algorithms/test_coupled_reflow.py`), the runs reproduce `cpu_dmc` "
        + ("to the last digit" if checked and same == checked else f"in {st.of(same, checked)} runs")
        + ", and the 1-step policy's one-step error is "
        + ("as large on its own states as on the 10-step policy's. " if close else "measured on both states. ")
        + (
            f"Nor is it saturation: the share of pre-tanh components beyond ±1 stays at {st.span(sat_n + sat_1)} at "
            f"N = 10 and N = 1 through training, about the initialisation's {init:.2f}."
            if no_saturation
            else f"Saturation is not ruled out as simply: the share of pre-tanh components beyond ±1 stays at "
            f"{st.span(sat_n)} at N = 10 through training (the initialisation's {init:.2f}), while at N = 1 it "
            f"reaches {max(sat_1):.2f} ({st.span(sat_1)}, on the 10-step policy's states); whether that matters is "
            "not tested here."
        )
    )
    out["mechanism"] = "\n".join(bullets)
    return out


def other_tasks(c: SimpleNamespace) -> dict:
    """The other tasks: cartpole_balance and reacher_easy."""
    ad_lam, below, cp, cp_multi, dmc, lam, others, re_, re_below, re_ref, runs, weakest = (
        c.ad_lam,
        c.below,
        c.cp,
        c.cp_multi,
        c.dmc,
        c.lam,
        c.others,
        c.re_,
        c.re_below,
        c.re_ref,
        c.runs,
        c.weakest,
    )
    out: dict = {}
    cp_err = {lb: statistics.fmean(runs(lb, cp, "one_step").values()) for lb in REFPO_VARIANTS}
    cp_ratio = statistics.fmean(runs("refpo", cp, "one_step_ratio").values())
    cp_one = runs("refpo", cp, ONE)
    re_err = {lb: statistics.fmean(runs(lb, re_, "one_step").values()) for lb in REFPO_VARIANTS}
    re_fall = {lb: len(re_below[lb]) for lb in others}
    all_re = [(v, lb, s) for lb in REFPO_VARIANTS for s, v in runs(lb, re_, MULTI).items()]
    best = max(all_re)
    re_lam = ad_lam[re_]
    fpo_re = runs("fpo", re_, MULTI, dmc) or runs("fpo", re_, MULTI)
    holds_cp = not any(st.collapsed(runs("refpo", cp, MULTI)[s], cp_one[s], below) for s in cp_one)
    out["other_tasks"] = (
        f"On cartpole_balance{', the task where ReFPO' + chr(39) + 's 1-step return holds,' if holds_cp else ','} "
        f"ReFPO's one-step error at the end of training is {cp_err['refpo']:.2f} on the evaluation states (ratio "
        f"{cp_ratio:.1f}) and the 1-step return is {st.pm(cp_one.values())}: balancing forgives a biased first step "
        "that point_mass's target does not (our reading). Coupled pairs and the adaptive λ bring the error to "
        f"{' and '.join(diag(cp_err[lb]) for lb in others)} and lift the 10-step return of ReFPO's weakest seed (seed "
        f"{weakest}: {cp_multi[weakest]:.1f}; "
        + ", ".join(f"{SHORT[lb]} {runs(lb, cp, MULTI).get(weakest, float('nan')):.1f}" for lb in others)
        + f"). On reacher_easy the one-step error falls as well ({' and '.join(diag(re_err[lb]) for lb in others)} "
        f"against {diag(re_err['refpo'])}) and the 10-step return falls below ReFPO's in "
        + " and ".join(f"{st.of(re_fall[lb], len(runs(lb, re_, MULTI)))} seeds with {SHORT[lb]}" for lb in others)
        + f" (seed {min(re_ref)}: independent pairs {re_ref[min(re_ref)]:.1f}, "
        + ", ".join(f"{SHORT[lb]} {runs(lb, re_, MULTI)[min(re_ref)]:.1f}" for lb in others)
        + f"). The adaptive λ ends between {re_lam['low']:g} and {re_lam['high']:g} across reacher's seeds (mean "
        f"{re_lam['mean']:.2g}); the best reacher run of the three ReFPO variants is seed {best[2]} of "
        f"{SHORT[best[1]]} ({best[0]:.1f}), while FPO (`cpu_dmc`) has {st.pm(fpo_re.values())}. Our reading: on "
        f"reacher a λ below the paper's {lam('refpo', re_)['mean']:g} may cost return, which would make the "
        "schedule's floor a "
        "questionable choice; the per-seed λ curves that would show it are not committed."
    )
    return out


def diagnostics_and_leads(c: SimpleNamespace) -> dict:
    """The diagnostics' ranges and the leads."""
    below, coef_of, e, k, none, pm_task, rm, ro, role, runs, s_pm, tasks = (
        c.below,
        c.coef_of,
        c.e,
        c.k,
        c.none,
        c.pm_task,
        c.rm,
        c.ro,
        c.role,
        c.runs,
        c.s_pm,
        c.tasks,
    )
    out: dict = {}
    s_all = [v for lb in REFPO_VARIANTS for t in tasks for v in runs(lb, t, "straightness").values()]
    out["straightness_range"] = st.span(s_all)
    ratio_eval = {lb: runs(lb, pm_task, "one_step_ratio") for lb in ("fpo", *REFPO_VARIANTS)}
    lost_r: list[float] = []
    kept_r: list[float] = []
    for lb, values in ratio_eval.items():
        m, o = runs(lb, pm_task, MULTI), runs(lb, pm_task, ONE)
        for s, v in values.items():
            (lost_r if st.collapsed(m[s], o[s], below) else kept_r).append(v)
    ref_r = ratio_eval["refpo"]
    ref_lost = sum(st.collapsed(rm[s], ro[s], below) for s in ref_r)
    out["diag_text"] = (
        f"collapsed in {st.of(ref_lost, len(ref_r))} seeds, they end at final ratios (eval) of "
        f"{st.span(ref_r.values())} while their Straightness is the lowest of the variants"
        if min(s_pm, key=s_pm.__getitem__) == "refpo"
        else f"collapsed in {st.of(ref_lost, len(ref_r))} seeds, they end at final ratios (eval) of "
        f"{st.span(ref_r.values())}"
    )
    overlap = kept_r and lost_r and min(lost_r) <= max(kept_r)
    out["diag_caveat"] = (
        f"over every point_mass run here (FPO and the three ReFPO variants), the collapsed runs end at ratios of "
        f"{st.span(lost_r)} and the runs that held at {st.span(kept_r)}, so the final ratio does not separate them."
        if overlap
        else f"over every point_mass run here the collapsed runs end at ratios of {st.span(lost_r)} and the runs "
        f"that held at {st.span(kept_r) if kept_r else 'none'}."
    )
    out["lead_coupled"] = (
        f"λ = {coef_of(role['coupled_high']):g} cut the error {none / e(role['coupled_high']):.1f}× in {k} iterations"
    )
    dmc_yaml = yaml.safe_load((st.ROOT / "configs" / "task" / "_dmc.yaml").read_text(encoding="utf-8"))
    cuda = dmc_yaml["by_device"]["cuda"]
    out["cuda_envs"] = cuda["num_envs"]
    out["cuda_steps"] = f"{cuda['total_env_steps'] / 1e6:g}M"
    return out
    return out
