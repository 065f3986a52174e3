"""The page's GridWorld part: the stages' evaluations (demonstrations, clones, fine-tuned runs), the goal bands'
shares, and the learning check's records of the same recipe."""

from __future__ import annotations

import ast
from collections import Counter

from number_text import seconds, span, thousands
from study_layout import (
    BOTH_BANDS,
    CHECK_RECORDS,
    CHECKS_SOURCE,
    HERE,
    KEPT,
    MOVE,
    ROWS,
    TIMEOUTS,
    read_json,
    read_yaml,
)

from refpo_warp.studies.reports.committed_runs import read_jsonl, seeds_text
from refpo_warp.studies.reports.phrases import and_list


def eval_settings(results: dict) -> list[tuple[str, str]]:
    """(eval.json key, the table's N) of the settings the table shows."""
    return [(s, s[2:] if s.startswith("N=") else "mean action") for s in ("N=1", "N=10", "mean_action") if s in results]


def unshown_settings(results: dict[str, dict]) -> list[str]:
    """The evaluation settings in the runs' eval.json that the table leaves out."""
    shown = {s for r in results.values() for s, _ in eval_settings(r)}
    return sorted({s for r in results.values() for s in r} - shown)


def gridworld_table() -> str:
    lines = ["| policy | N | success | top share | bottom share | episode length |", "|---|---|---|---|---|---|"]
    d = read_json(KEPT / "clone_flow" / "eval.json")["dataset"]
    lines.append(
        f"| demonstrations (scripted, {d['episodes']:,} episodes) | - | {d['success_rate']:.3f} | "
        f"{d['top_share']:.3f} | {d['bottom_share']:.3f} | {d['length_mean']:.2f} |"
    )
    for name, what in ROWS:
        results = read_json(KEPT / name / "eval.json")["results"]
        for setting, n in eval_settings(results):
            r = results[setting]
            lines.append(
                f"| {what} | {n} | {r['success_rate']:.3f} | {r['top_share']:.3f} | "
                f"{r['bottom_share']:.3f} | {r['length_mean']:.1f} |"
            )
    return "\n".join(lines)


def gridworld_values() -> dict:
    from refpo_warp.tasks.gridworld.cfg import GridWorldCfg

    evals = {name: read_json(KEPT / name / "eval.json") for name, _ in ROWS}
    configs = {name: read_yaml(KEPT / name / "config.yaml") for name, _ in ROWS}
    meta = read_json(KEPT / "data" / "metadata.json")["refpo"]
    policy = meta["policy"]
    size = GridWorldCfg(**configs["clone_flow"]["env"]).size
    timeout = GridWorldCfg(**configs["clone_flow"]["env"]).max_episode_length
    mid = (size - 1) // 2
    res = {name: e["results"] for name, e in evals.items()}
    flow_clone, gauss = res["clone_flow"]["N=10"], res["clone_gauss"]["mean_action"]
    refpo, fpo, ppo = res["refpo_from_flow"], res["fpo_from_flow"], res["ppo_from_gauss"]["mean_action"]
    data = evals["clone_flow"]["dataset"]
    ft = [n for n, _ in ROWS if not n.startswith("clone")]
    ft_cfg = configs["refpo_from_flow"]
    per_iteration = ft_cfg["num_envs"] * ft_cfg["runner"]["num_steps_per_env"]
    steps = evals["refpo_from_flow"]["env_steps"]
    assert all(evals[n]["env_steps"] == steps for n in ft), "the GridWorld fine-tuning runs differ in env steps"
    scratch_steps = configs["clone_flow"]["total_env_steps"]  # the task's own budget (the clones' config)
    unshown = unshown_settings(res)
    episodes = {r["episodes"] for results in res.values() for r in results.values()}
    with_unshown = [n for n, _ in ROWS if set(res[n]) & set(unshown_settings(res))]
    normalised = [
        name
        for name, cfg in configs.items()
        if cfg["actor"].get("obs_normalization") or cfg["critic"].get("obs_normalization")
    ]
    fails = round((1 - gauss["success_rate"]) * gauss["episodes"])

    # the Gaussian clone's time-outs
    if TIMEOUTS.exists():
        rows = {int(y): k for y, k in read_json(TIMEOUTS).items()}
        timeouts = (
            f"By the row they end in (rolled out again by `tables.py --keep`, {TIMEOUTS.relative_to(HERE)}): "
            + ", ".join(f"row {y}: {k}" for y, k in sorted(rows.items()))
            + "."
        )
    else:
        timeouts = (
            "Where they stood when the time-out ended them was counted once, by rolling the clone's checkpoint out "
            "again (`timeout_rows` in `tables.py`); neither the checkpoint nor the counts were kept, so this page "
            "does not report them (`tables.py --keep` keeps them in `gridworld/clone_gauss/timeout_rows.json` "
            "when the checkpoint is there)."
        )

    def shares(r: dict) -> str:
        return f"top {r['top_share']:.3f} / bottom {r['bottom_share']:.3f}"

    minority = "bottom" if data["bottom_share"] < data["top_share"] else "top"
    flipped = [name for name, r in (("ReFPO", refpo["N=10"]), ("FPO", fpo["N=10"])) if r[f"{minority}_share"] > 0.5]
    if len(flipped) == 2:
        flip = f"the data's minority band ({minority}) becomes the majority at N = 10 in both"
    elif flipped:
        flip = f"the data's minority band ({minority}) becomes the majority at N = 10 for {flipped[0]} only"
    else:
        flip = f"the data's minority band ({minority}) stays the minority at N = 10 in both"
    n1_cmp = "shorter" if fpo["N=1"]["length_mean"] < refpo["N=1"]["length_mean"] else "longer"
    length_words = [
        "shorter" if r["N=10"]["length_mean"] < flow_clone["length_mean"] else "longer" for r in (refpo, fpo)
    ]
    lengths = (
        f"episodes at N = 10 get {length_words[0]} for ReFPO ({flow_clone['length_mean']:.1f} → "
        f"{refpo['N=10']['length_mean']:.1f}) and {length_words[1]} for FPO ({fpo['N=10']['length_mean']:.1f})"
    )

    def bands(*rs: dict) -> str:
        kept = [min(r["top_share"], r["bottom_share"]) >= BOTH_BANDS for r in rs]
        return "both bands kept" if all(kept) else "both bands kept in " + f"{sum(kept)} of {len(kept)}"

    return {
        "gw_both_bands": f"{BOTH_BANDS:g}",
        "gw_flow_bands": bands(flow_clone),
        "gw_ft_bands": bands(refpo["N=10"], fpo["N=10"]),
        "gw_band": f"{mid - policy['band']}-{mid + policy['band']}",
        "gw_mid": mid,
        "gw_size": size,
        "gw_up": f"{policy['up_share']:g}",
        "gw_down": f"{1 - policy['up_share']:g}",
        "gw_mean": (
            f"({2 * policy['up_share'] - 1:g}) "
            + ("rounds to no move" if abs(2 * policy["up_share"] - 1) <= MOVE else "still moves")
            + f" (the env moves an axis only where |a| > {MOVE:g})"
        ),
        "gw_episodes": f"{read_json(KEPT / 'data' / 'metadata.json')['total_episodes']:,}",
        "gw_steps": f"{read_json(KEPT / 'data' / 'metadata.json')['total_steps']:,}",
        "gw_collect": f"{meta['collect_time_s']:.1f}",
        "gw_collect_envs": meta["num_envs"],
        "gw_epochs": configs["clone_flow"]["pretrain"]["epochs"],
        "gw_patience": configs["clone_flow"]["pretrain"]["patience"],
        "gw_ft_steps": thousands(steps),
        "gw_ft_iterations": steps // per_iteration,
        "gw_ft_share": f"{steps / scratch_steps:.2f}",
        "gw_scratch_steps": thousands(scratch_steps),
        "gw_warmup": ft_cfg["critic_warmup_iterations"],
        "gw_seed": seeds_text({configs[n]["seed"] for n in configs}),
        "gw_eval_episodes": seeds_text(episodes),
        "gw_unshown": (
            f"{and_list([s.replace('=', ' = ') for s in unshown])} also in the eval.json of "
            + (
                "every flow run"
                if set(with_unshown) == {n for n in res if "N=10" in res[n]}
                else and_list(with_unshown)
            )
            if unshown
            else "nothing else in the eval.json files"
        ),
        "gw_normalisers": (
            "GridWorld's actors and critics normalise no observation (`obs_normalization: false` in every "
            "config.yaml here), so `clone_normalizer` (below) changes nothing here."
            if not normalised
            else f"The runs {', '.join(normalised)} normalise their observations."
        ),
        "gridworld_table": gridworld_table(),
        "gw_timeout": timeout,
        "gw_fails": fails,
        "gw_gauss_episodes": gauss["episodes"],
        "gw_timeouts": timeouts,
        "gw_flow_success": f"{flow_clone['success_rate']:.2f}",
        "gw_flow_shares": shares(flow_clone),
        "gw_data_shares": shares(data),
        "gw_gauss_success": f"{gauss['success_rate']:.2f}",
        "gw_ft_success": f"{refpo['N=10']['success_rate']:.2f} and {fpo['N=10']['success_rate']:.2f}",
        "gw_ft_smaller": (
            f"{min(refpo['N=10']['top_share'], refpo['N=10']['bottom_share']):.3f} and "
            f"{min(fpo['N=10']['top_share'], fpo['N=10']['bottom_share']):.3f}"
        ),
        "gw_flip": flip,
        "gw_lengths": lengths,
        "gw_n1": (
            f"ReFPO succeeds in {refpo['N=1']['success_rate']:.2f} of its episodes ({shares(refpo['N=1'])}), FPO in "
            f"{fpo['N=1']['success_rate']:.2f} ({shares(fpo['N=1'])}); in this seed FPO's N = 1 episodes were "
            f"{n1_cmp} than ReFPO's ({fpo['N=1']['length_mean']:.1f} against {refpo['N=1']['length_mean']:.1f} "
            "steps)"
        ),
        "gw_ppo": (
            f"{gauss['success_rate']:.2f} → {ppo['success_rate']:.2f} ({shares(ppo)}; episodes "
            f"{gauss['length_mean']:.1f} → {ppo['length_mean']:.1f} steps)"
        ),
        "gw_times": (
            f"collecting {seconds(meta['collect_time_s'])}, the flow clone "
            f"{seconds(evals['clone_flow']['pretrain']['time_s'])} ({evals['clone_flow']['pretrain']['epochs_run']} "
            f"epochs), the Gaussian clone {seconds(evals['clone_gauss']['pretrain']['time_s'])} "
            f"({evals['clone_gauss']['pretrain']['epochs_run']} epochs), fine-tuning ReFPO "
            f"{seconds(evals['refpo_from_flow']['train_time_s'])}, "
            f"FPO {seconds(evals['fpo_from_flow']['train_time_s'])}, "
            f"PPO {seconds(evals['ppo_from_gauss']['train_time_s'])}"
        ),
    }


def record_note(records: list[dict]) -> str:
    """Which seeds the records hold more than once, and whether their statistics agree."""
    twice = sorted(seed for seed, n in Counter(r["seed"] for r in records).items() if n > 1)
    if not twice:
        return "one per seed"
    threads = sorted({str(r["threads"]) for r in records if r["seed"] in twice})

    def statistics(r: dict) -> tuple:
        return tuple(r["final"][s][k] for s in ("N=1", "N=10") for k in ("length_mean", "top_share", "bottom_share"))

    alike = all(len({statistics(r) for r in records if r["seed"] == seed}) == 1 for seed in twice)
    return f"seeds {seeds_text(twice)} recorded more than once, with {and_list(threads)} torch threads" + (
        ", alike in these statistics" if alike else ", differing in these statistics"
    )


def learning_check_values() -> dict:
    """The learning check's records: each run's statistics as tests/learning/checks.py computes them."""
    records = read_jsonl(CHECK_RECORDS)
    constants: dict[str, str] = {}
    for node in ast.parse(CHECKS_SOURCE.read_text()).body:
        if not isinstance(node, ast.Assign):
            continue
        target = node.targets[0]
        if isinstance(target, ast.Name) and target.id in ("FINETUNE_COLLECT", "FINETUNE_PRETRAIN"):
            constants.update(o.split("=", 1) for o in ast.literal_eval(node.value))

    def ratio(r: dict, s: str) -> float:
        return r["final"][s]["length_mean"] / r["initial"][s]["length_mean"]

    learning = [r for r in records if not r["null"]]
    null = [r for r in records if r["null"]]
    overrides = dict(o.split("=", 1) for o in learning[0]["overrides"])
    change = [r["final"]["N=10"]["bottom_share"] - r["initial"]["N=10"]["bottom_share"] for r in learning]
    smaller = [min(r["final"]["N=10"]["top_share"], r["final"]["N=10"]["bottom_share"]) for r in learning]
    if min(change) < 0 < max(change):
        moves = "moving either way over the seeds, so the one-seed flip in the table above is not a rule"
    elif min(change) >= 0:
        moves = "never falling in any seed"
    else:
        moves = "falling in every seed"
    return {
        "lc_seeds": seeds_text({r["seed"] for r in learning}),
        "lc_records": len(learning),
        "lc_record_note": record_note(learning),
        "lc_episodes": constants["episodes"],
        "lc_epochs": constants["pretrain.epochs"],
        "lc_iterations": overrides["max_iterations"],
        "lc_warmup": overrides["critic_warmup_iterations"],
        "lc_env_steps": thousands(learning[0]["rows"][-1]["env_steps"]),
        "lc_n1": span([ratio(r, "N=1") for r in learning], 3),
        "lc_n10": span([ratio(r, "N=10") for r in learning], 3),
        "lc_null_seeds": seeds_text({r["seed"] for r in null}),
        "lc_null_n1": span([ratio(r, "N=1") for r in null], 2),
        "lc_null_n10": span([ratio(r, "N=10") for r in null], 2),
        "lc_smaller": f"{min(smaller):.2f}",
        "lc_change": f"{min(change):+.3f} to {max(change):+.3f}, {moves}",
    }
