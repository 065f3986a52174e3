#!/usr/bin/env python
"""docs/results/learning_checks.md, from learning_checks.template.md and the files it reads:

    python docs/results/learning_checks_page.py [--check]

- the checks (``tests/learning/checks.py``: which run in CI, their overrides, bounds and CI minutes, the null
  control) and the runs the rule asks for (``tests/learning/table.py``);
- their records (``learning_checks/records/*.jsonl``, read by ``tests/learning/measure.py``): every statistic the
  prose names, and the table that ``python tests/learning/measure.py table`` writes between its markers (the same
  code, ``table.table_markdown``);
- the two logs of checks run again after a change (``learning_checks/*.log``: their ``[learning check]`` lines);
- the fine-tuning study's GridWorld dataset (``finetuning/gridworld/clone_flow/eval.json``: the demonstrator's band
  shares) and the shipped profiles (``configs/``, resolved as ``refpo train`` resolves them).
"""

from __future__ import annotations

import json
import math
import re
import sys
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "tests" / "learning"))
sys.path.insert(0, str(HERE))
from checks import CHECKS, FINETUNE_COLLECT, FINETUNE_PRETRAIN, MJLAB_NULL_CONTROL, NULL_CONTROL  # noqa: E402
from measure import RECORDS, RESULTS, current, read_records  # noqa: E402
from results_reading import profile, steps_text  # noqa: E402  (docs/results/results_reading.py)
from table import LEARNING_RUNS, NULL_RUNS, fmt, table_markdown  # noqa: E402

from refpo_warp.studies.reports.committed_runs import read_jsonl, seeds_text  # noqa: E402
from refpo_warp.studies.reports.phrases import and_list  # noqa: E402
from refpo_warp.studies.reports.results_page import main_args, write_page  # noqa: E402

TEMPLATE = HERE / "learning_checks.template.md"
LOG_LINE = re.compile(r"^\[learning check\] (\S+): (.*?); bounds")


def code(items) -> str:
    return ", ".join(f"`{i}`" for i in items)


def override(check: str, key: str) -> str | None:
    return next((o.split("=", 1)[1] for o in CHECKS[check].overrides if o.startswith(key + "=")), None)


def runs(records, check: str, null: bool | None = None, threads: int | None = None) -> list[dict]:
    return [
        r
        for r in records
        if r["check"] == check and (null is None or r["null"] == null) and (threads is None or r["threads"] == threads)
    ]


def lo_hi(values, form=fmt) -> str:
    """``lo-hi`` (``lo to hi`` where lo is negative) of ``values``, each written by ``form``."""
    values = list(values)
    if min(values) == max(values):
        return form(values[0])
    return f"{form(min(values))}{' to ' if min(values) < 0 else '-'}{form(max(values))}"


def whole(v: float) -> str:
    return f"{v:.0f}"


# ------------------------------------------------------------------------------------------------ the sections
def ci(records) -> dict[str, str]:
    in_ci = [c for c in CHECKS.values() if c.in_ci]
    plain = [f"`{c.name}`" for c in in_ci if c.runner != "mjlab"]
    mjlab = [f"`{c.name}`" for c in in_ci if c.runner == "mjlab"]
    demand = [c for c in CHECKS.values() if not c.in_ci]
    return {
        "ci_count": str(len(in_ci)),
        "ci_list": ", ".join(plain) + (f" and, in the mjlab job, {and_list(mjlab)}" if mjlab else ""),
        "demand_count": f"The other {len(demand)}",
        "demand_list": code(c.name for c in demand),
        "demand_minutes": f"{sum(c.minutes for c in demand):.0f}",
        "null_control": " and ".join(f"`{o}`" for o in NULL_CONTROL),
        "mjlab_null": f"`{' '.join(MJLAB_NULL_CONTROL)}`",
        "learning_runs": " and ".join(
            f"seeds {seeds_text(seeds)} with {threads} torch thread{'s' if threads > 1 else ''}"
            for threads, seeds in LEARNING_RUNS.items()
        )
        + f" (the null control: seeds {seeds_text(NULL_RUNS)}, one thread)",
        "no_periodic": and_list([f"`{c.name}`" for c in CHECKS.values() if "eval.interval=0" in c.overrides]),
    }


def cpus(records) -> str:
    """Per kind of run (one thread, the null control, two threads), the CPU most of its records name and the checks
    whose records name another."""
    out = []
    for what, pick in (
        ("the one-thread learning runs", lambda r: not r["null"] and r["threads"] == 1),
        ("the null controls", lambda r: r["null"]),
        ("the two-thread runs", lambda r: not r["null"] and r["threads"] == 2),
    ):
        mine = [r for r in records if pick(r)]
        if not mine:
            continue
        main = Counter(r["cpu"] for r in mine).most_common(1)[0][0]
        others: dict[str, dict[str, list[int]]] = {}
        for r in mine:
            if r["cpu"] != main:
                others.setdefault(r["cpu"], {}).setdefault(r["check"], []).append(r["seed"])
        text = f"{what} on {main}"
        if others:
            text += (
                " ("
                + "; ".join(
                    f"on {cpu}: "
                    + ", ".join(
                        f"`{check}` seed{'s' if len(seeds) > 1 else ''} {seeds_text(seeds)}"
                        for check, seeds in by.items()
                    )
                    for cpu, by in others.items()
                )
                + ")"
            )
        out.append(text)
    return "; ".join(out) + "."


def isolation(records) -> str:
    """Seed 1 of the CI checks run again after evaluation was isolated: the log's statistics, against the record."""
    log = RESULTS / "seed1_after_evaluation_isolation.log"
    parts, inside = [], True
    for line in log.read_text(encoding="utf-8").splitlines():
        match = LOG_LINE.match(line)
        if not match:
            continue
        name, stats_text = match.groups()
        stats = {k: float(v) for k, v in (item.rsplit(" ", 1) for item in stats_text.split(", "))}
        inside &= all(b.holds(stats) for b in CHECKS[name].bounds if b.statistic in stats)
        record = next((r for r in runs(records, name, False, 1) if r["seed"] == 1), None)
        was = CHECKS[name].statistics(record) if record else {}
        parts.append(
            f"`{name}` "
            + ", ".join(
                f"{k} {fmt(v)}" + (f" (the record: {fmt(was[k])})" if k in was else "") for k, v in stats.items()
            )
        )
    verdict = "each inside its bounds" if inside else "not every one inside its bounds"
    return (
        f"The first seed of {len(parts)} such checks CI runs, trained again after the change on one thread: "
        + "; ".join(parts)
        + f"; {verdict}."
    )


def fpo_pp_own(records) -> str:
    log = RESULTS / "cartpole_fpo_pp_seed1_own_values.log"
    match = next(m for m in map(LOG_LINE.match, log.read_text(encoding="utf-8").splitlines()) if m)
    stats = {k: float(v) for k, v in (item.rsplit(" ", 1) for item in match.group(2).split(", "))}
    bounds = CHECKS["cartpole_fpo_pp"].bounds
    holds = all(b.holds(stats) for b in bounds if b.statistic in stats)
    return (
        f"Its first seed with FPO++'s own values {'meets' if holds else 'fails'} the bound ("
        + ", ".join(f"{k} {fmt(v)}" for k, v in stats.items())
        + f" against `{'`, `'.join(str(b) for b in bounds)}`; `learning_checks/{log.name}`)."
    )


def finetune(records) -> str:
    name = "gridworld_finetune_refpo"
    check, mine = CHECKS[name], runs(records, name)
    learning = runs(records, name, False)
    collect = dict(o.split("=", 1) for o in FINETUNE_COLLECT)
    pretrain = dict(o.split("=", 1) for o in FINETUNE_PRETRAIN)
    study = json.loads((HERE / "finetuning" / "gridworld" / "clone_flow" / "eval.json").read_text())["dataset"]
    change = [check.statistics(r)["bottom_share_change_N=10"] for r in learning]
    one_way = all(c > 0 for c in change) or all(c < 0 for c in change)
    by_seed: dict[int, dict[int, dict]] = {}
    for r in learning:
        by_seed.setdefault(r["seed"], {})[r["threads"]] = check.statistics(r)
    both = [s for s, by in by_seed.items() if len(by) > 1]
    same = all(len({json.dumps(v, sort_keys=True) for v in by_seed[s].values()}) == 1 for s in both)
    wall = max(mine, key=lambda r: r["wall_s"])
    iterations, warmup = override(name, "max_iterations"), override(name, "critic_warmup_iterations")
    return (
        f"`{name}` collects {collect['episodes']} episodes of GridWorld's scripted two-mode demonstrator "
        f"(`tasks/gridworld/demonstrator.py`; in the fine-tuning study's {study['episodes']} episodes the top band "
        f"takes {study['top_share']:.2f} of them, the bottom {study['bottom_share']:.2f}: "
        "`finetuning/gridworld/clone_flow/eval.json`), clones the flow actor from them (`refpo pretrain`, "
        f"{pretrain['pretrain.epochs']} epochs at most, {pretrain['pretrain.num_pairs']} (tau, eps) pairs per action), "
        f"then fine-tunes the clone with ReFPO for {iterations} iterations "
        f"({mine[0]['rows'][-1]['env_steps']:,} env steps), the first {warmup} the critic's warm-up (`init_from`, "
        "`critic_warmup_iterations`; `docs/finetuning.md`); each seed collects and clones its own. Its initial policy "
        "is the clone, evaluated in the fine-tuning run's protocol, and its null control switches the fine-tuning's "
        "learning off (the clone is what it starts from). It reads the episode length at N = 1 and 10 over the "
        "clone's (the clone's flow wanders, most at N = 1; the fine-tuned one walks to a band) and asserts that both "
        "goal bands keep a share of the successes (`both_bands_kept`). The data's minority band's share "
        + (
            "moves one way at this budget"
            if one_way
            else "does not move one way at this budget (its change at N = 10 over the learning runs: "
            f"{min(change):+.3f} to {max(change):+.3f})"
        )
        + ", and no bound reads it. Its records were made on "
        + and_list(sorted({r["cpu"] for r in mine}))
        + f" (wall times up to {wall['wall_s']:.0f} s, a {wall['threads']}-thread run); its two-thread runs "
        + ("equal" if same else "differ from")
        + " the one-thread runs of the same seed in every statistic"
        + (", so for this check they stand for no other CPU." if same else ".")
    )


def fpo_pp_narrow(records) -> str:
    check = CHECKS["cartpole_fpo_pp"]
    learning, null = runs(records, check.name, False), runs(records, check.name, True)
    refpo = runs(records, "cartpole_refpo", False)
    settings = [s for s in learning[0]["final"] if s in learning[0]["initial"]]
    one = runs(records, check.name, False, 1)
    gain = [r["final"]["N=10"]["return_mean"] / r["initial"]["N=10"]["return_mean"] for r in one]
    null_gain = [r["final"]["N=10"]["return_mean"] / r["initial"]["N=10"]["return_mean"] for r in null]
    steps = learning[0]["rows"][-1]["env_steps"]
    return (
        f"At the cartpole's {steps_text(steps)} env steps FPO++'s N = 10 return goes from "
        f"{lo_hi([r['initial']['N=10']['return_mean'] for r in learning], whole)} to "
        f"{lo_hi([r['final']['N=10']['return_mean'] for r in learning], whole)} over its "
        f"{len(learning)} learning runs, where ReFPO's reach "
        f"{lo_hi([r['final']['N=10']['return_mean'] for r in refpo], whole)} (FPO++'s records are of "
        f"its earlier values, above), and one evaluation setting's gain (N = 10: {lo_hi(gain)} over seeds "
        f"{seeds_text(r['seed'] for r in one)}, one thread) sits close to the null control's (up to "
        f"{fmt(max(null_gain))}): its bound reads the mean of {len(settings)} settings' gains ({code(settings)}), "
        f"which averages {len(settings)} times the episodes."
    )


def one_step(records) -> str:
    name = "point_mass_refpo_onestep"
    check = CHECKS[name]
    first = next(b for b in check.bounds if not b.claim)
    claim = next(b for b in check.bounds if b.claim)
    learning, null, mine = runs(records, name, False), runs(records, name, True), runs(records, name)
    stats = {id(r): check.statistics(r) for r in mine}
    meets = [r for r in null if claim.holds(stats[id(r)])]
    episodes = {r["final"][s]["episodes"] for r in mine for s in r["final"]}
    profile_episodes = profile("dmc_point_mass", "refpo_onestep")["eval"]["num_envs"]
    std = [r["final"]["N=10"]["return_std"] for r in learning]
    # the standard error of a profile-sized evaluation's mean, relative to that mean, per learning run
    se = [
        r["final"]["N=10"]["return_std"] / math.sqrt(profile_episodes) / r["final"]["N=10"]["return_mean"]
        for r in learning
    ]
    ratios = [(stats[id(r)][claim.statistic], r) for r in learning]
    lowest, low_run = min(ratios, key=lambda x: x[0])
    return (
        f"`{name}` trains `algo=refpo_onestep` through the whole CPU profile of `dmc_point_mass` "
        f"({learning[0]['rows'][-1]['env_steps']:,} env steps, no periodic evaluations), past the env steps where the "
        "paper's ReFPO's N = 1 return collapsed on this task (`docs/results/one_step/search.md`). Its first bound: the "
        f"N = 10 return rises at least {first.value:g} above the initial policy's (the initial policies of its "
        f"{len(mine)} runs score {lo_hi([r['initial']['N=10']['return_mean'] for r in mine], whole)} "
        f"at N = 10; the learning runs rise {lo_hi([stats[id(r)][first.statistic] for r in learning], whole)}"
        f", the null control {lo_hi([stats[id(r)][first.statistic] for r in null], whole)}). Its "
        f"second is the configuration's promise, N = 1 return at least {claim.value:g} × N = 10 return, a claim "
        "bound: "
        + (
            f"the null control meets it alone in {len(meets)} of {len(null)} seeds ("
            + ", ".join(
                f"seed {r['seed']}: {r['final']['N=1']['return_mean']:.1f} against "
                f"{r['final']['N=10']['return_mean']:.1f}"
                for r in meets
            )
            + "), as two returns near zero can"
            if meets
            else "the null control does not meet it"
        )
        + ", so the first bound is the one the null control fails. Both read "
        + f"{' or '.join(str(e) for e in sorted(episodes))} episodes per setting, where the profile evaluates "
        f"{profile_episodes}: the N = 10 return's spread over episodes (its std {lo_hi(std, whole)} in "
        f"the learning runs) leaves a {profile_episodes}-episode mean a standard error of "
        f"{lo_hi([100 * s for s in se], whole)} % of it, against "
        f"{fmt(lowest - claim.value)} between the claim and the lowest run's ratio ({fmt(lowest)}, seed "
        f"{low_run['seed']}, {low_run['threads']} thread{'s' if low_run['threads'] > 1 else ''}). It evaluates random "
        f"initial noise only (`eval.initial_noise=[random]`; the configuration also evaluates zero noise, which the "
        f"check does not read). {same_as_earlier(name)}"
    )


def same_as_earlier(name: str) -> str:
    """Whether every current record equals the earlier record (other overrides) of the same seed, thread count and
    control in its statistics' inputs, training curve and diagnostics."""
    path = RECORDS / f"{name}.jsonl"
    every = read_jsonl(path)
    now = [r for r in every if current(r)]
    earlier = {(r["seed"], r["threads"], r["null"]): r for r in every if not current(r)}
    found = [(r, earlier.get((r["seed"], r["threads"], r["null"]))) for r in now]
    pairs = [(r, e) for r, e in found if e is not None]
    if not pairs:
        return ""

    def same(r: dict, e: dict) -> bool:
        settings = [s for s in r["final"] if s in e["final"]]
        return (
            all(r[k][s] == e[k][s] for k in ("initial", "final") for s in settings)
            and r["rows"] == e["rows"]
            and r["diagnostics"] == e["diagnostics"]
        )

    equal = sum(same(r, e) for r, e in pairs)
    verdict = (
        "every run's evaluations, training curve and diagnostics equal those of the earlier record of the same "
        "seed, thread count and control, to the bit"
        if equal == len(pairs)
        else f"{equal} of {len(pairs)} runs equal the earlier record of the same seed, thread count and control"
    )
    return (
        f"Its records were made again when CI took it in, with that override and with denormals flushed: {verdict} "
        f"(the earlier records stay in `records/{path.name}`, with their own overrides)."
    )


def profiles() -> dict[str, str]:
    grpo = profile("dmc_cartpole_balance", "flow_grpo")
    rein = profile("dmc_cartpole_balance", "reinflow")
    fpo_pp = profile("dmc_cartpole_balance", "fpo_pp")
    return {
        "fpo_pp_flow_steps": str(fpo_pp["actor"]["num_flow_steps"]),
        "flow_grpo": (
            f"`env.max_episode_length={grpo['env']['max_episode_length']}` (a rollout of "
            f"`runner.num_steps_per_env={grpo['runner']['num_steps_per_env']}` steps holds whole training episodes), "
            f"`num_envs={grpo['num_envs']}`, `algorithm.learning_rate={grpo['algorithm']['learning_rate']:g}`, "
            f"`total_env_steps={grpo['total_env_steps']}`"
        ),
        "reinflow": (
            f"`algorithm.schedule={rein['algorithm']['schedule']}` at "
            f"`algorithm.desired_kl={rein['algorithm']['desired_kl']:g}` from "
            f"`algorithm.learning_rate={rein['algorithm']['learning_rate']:g}`, `num_envs={rein['num_envs']}`, "
            f"`env.action_chunk={rein['env']['action_chunk']}`, `total_env_steps={rein['total_env_steps']}`"
            + (f", `max_iterations={rein['max_iterations']}`" if rein["max_iterations"] else "")
        ),
    }


def reinflow_gridworld(records) -> str:
    mine = runs(records, "gridworld_reinflow")
    setting = next(s for s in mine[0]["initial"] if s != "N=1")
    success = [r["initial"][setting]["success_rate"] for r in mine]
    return (
        f"On GridWorld ReinFlow's initial policies already succeed in {lo_hi(success, lambda v: f'{v:.2f}')} of "
        f"their episodes (`{setting}`, the initial evaluations of `gridworld_reinflow`'s {len(mine)} records), so its "
        "check reads the episode length, not the success rate."
    )


def values() -> dict[str, str]:
    records = read_records()
    return {
        **ci(records),
        **profiles(),
        "cpus": cpus(records),
        "isolation": isolation(records),
        "fpo_pp_own": fpo_pp_own(records),
        "finetune": finetune(records),
        "fpo_pp_narrow": fpo_pp_narrow(records),
        "one_step": one_step(records),
        "table": table_markdown(records),
        "reinflow_gridworld": reinflow_gridworld(records),
    }


def main() -> None:
    args = main_args(__doc__.split("\n\n")[0]).parse_args()
    same = write_page(TEMPLATE, values(), check=args.check)
    if args.check and not same:
        sys.exit(1)
    print(f"{TEMPLATE.with_name('learning_checks.md')}: {'unchanged' if same else 'written'}")


if __name__ == "__main__":
    main()
