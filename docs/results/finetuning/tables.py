"""docs/results/finetuning/README.md, written whole from README.template.md and the study's committed files
(gridworld.sh, dmc.sh; nothing on the page is typed by hand).

    python docs/results/finetuning/tables.py [--check]                          # the page from the committed files
    python docs/results/finetuning/tables.py --keep [--runs runs/finetuning/gridworld]
    python docs/results/finetuning/tables.py --dmc

Reads: gridworld/ (each GridWorld stage's config.yaml, eval.json, progress.jsonl and the dataset's metadata.json);
dmc/, normalizers_updated/ and scratch/ (the DMC demonstrators, datasets, clones and every fine-tuning and
from-scratch run: the normalisers held, updated from the rollouts, from scratch); ../cpu_dmc/per_task.csv (PPO's final
return at the full CPU profile); ../learning_checks/records/gridworld_finetune_refpo.jsonl and
tests/learning/checks.py (the learning check's records and its collection and cloning options).

``--keep`` first copies the GridWorld runs' small files from ``--runs`` into gridworld/ and, where the Gaussian
clone's checkpoint is there, rolls the clone out again and keeps where its time-outs end
(gridworld/clone_gauss/timeout_rows.json). ``--dmc`` first copies the DMC runs' small files (runs/finetuning/dmc and
the sweeps of DMC_SOURCES under runs/sweeps) into dmc/, normalizers_updated/ and scratch/, and draws dmc_curves.png
(fine-tuned and from-scratch evaluation curves side by side) and dmc_remedies.png (ReFPO's fine-tuning beside each
remedy tried against its collapse). ``--check`` writes nothing: it compares the page with what the files say.

Intervals: the mean over seeds with rliable's 95 % stratified bootstrap interval, and rliable's probability of
improvement (refpo_warp/studies/reports/intervals.py).
"""

from __future__ import annotations

import argparse
import ast
import csv
import functools
import json
import math
import shutil
import sys
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.intervals import Estimate, aggregate, improvement

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
TEMPLATE = HERE / "README.template.md"
KEPT = HERE / "gridworld"
DMC_KEPT = HERE / "dmc"  # the demonstrator, data and clones, and the fine-tuning runs (clone_normalizer=keep)
UPDATED_KEPT = HERE / "normalizers_updated"  # fine-tuning runs whose normalisers followed the rollouts, remedies tried
SCRATCH_KEPT = HERE / "scratch"  # from scratch at the fine-tuning runs' env steps
DMC_TASKS = ("dmc_point_mass", "dmc_reacher_easy")
DMC_METHODS = (  # (sweep label, the method it varies, name); the variants are the remedies tried for ReFPO's collapse
    ("refpo", "refpo", "ReFPO"),
    ("refpo_action_noise_std0.02", "refpo", "ReFPO, action noise 0.02"),
    ("refpo_action_noise_std0.05", "refpo", "ReFPO, action noise 0.05"),
    ("refpo_lr1e-4", "refpo", "ReFPO, learning rate 1e-4"),
    ("refpo_adaptive", "refpo", "ReFPO, adaptive λ"),
    ("refpo_aspo", "refpo", "ReFPO, ASPO trust region"),
    ("refpo_onestep", "refpo_onestep", "refpo_onestep"),
    ("refpo_onestep_action_noise_std0.02", "refpo_onestep", "refpo_onestep, action noise 0.02"),
    ("refpo_onestep_action_noise_std0.05", "refpo_onestep", "refpo_onestep, action noise 0.05"),
    ("ppo", "ppo", "PPO"),
    ("ppo_lr1e-4", "ppo", "PPO, learning rate 1e-4"),
)
NAMES = {label: name for label, _, name in DMC_METHODS}


def prose(label: str) -> str:
    """A run's name inside a sentence: 'ReFPO with adaptive λ', '`refpo_onestep`'."""
    head, _, tail = NAMES[label].partition(", ")
    return (f"{head} with {tail}" if tail else head).replace("refpo_onestep", "`refpo_onestep`")


# (where the runs are kept, the sweeps they come from by task name, how they started)
DMC_SOURCES = (
    (DMC_KEPT, ("finetune_{}", "finetune_remedies_keep_{}"), "the {clone}"),
    (
        UPDATED_KEPT,
        ("finetune_normupdate_{}", "finetune_floor_{}", "finetune_remedies_{}"),
        "the {clone}, normalisers updated",
    ),
    (SCRATCH_KEPT, ("finetune_scratch",), "scratch"),
)
DMC_FIGURE, REMEDIES_FIGURE = HERE / "dmc_curves.png", HERE / "dmc_remedies.png"
FROM_SCRATCH = HERE.parent / "cpu_dmc" / "per_task.csv"  # PPO's final return at the full CPU profile
CHECK_RECORDS = HERE.parent / "learning_checks" / "records" / "gridworld_finetune_refpo.jsonl"
CHECKS_SOURCE = ROOT / "tests" / "learning" / "checks.py"
ROWS = [  # (run folder, what it is)
    ("clone_flow", "flow clone (refpo pretrain algo=refpo)"),
    ("clone_gauss", "Gaussian clone (refpo pretrain algo=ppo)"),
    ("refpo_from_flow", "ReFPO fine-tuned from the flow clone"),
    ("fpo_from_flow", "FPO fine-tuned from the flow clone"),
    ("ppo_from_gauss", "PPO fine-tuned from the Gaussian clone"),
]
FILES = ("config.yaml", "eval.json", "progress.jsonl")
TIMEOUTS = KEPT / "clone_gauss" / "timeout_rows.json"
BOTH_BANDS = 0.2  # each goal band's least share of the successes (tests/learning/checks.py: both_bands_kept)
MOVE = 0.5  # GridWorld moves an axis only where |action| > MOVE (tasks/gridworld/env.py: rounded to {-1, 0, 1})
FALL = 0.5  # a run "falls" when its last periodic N = 10 return is below this share of its peak
FLOWS_HELD = ("refpo", "refpo_adaptive", "refpo_aspo", "refpo_onestep")  # fine-tuned flows, normalisers held


# ------------------------------------------------------------------------------------------------ formatting
def words(items: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def span(values, digits: int = 0, sep: str = "-") -> str:
    """'lowest-highest' (one value when they round alike)."""
    low, high = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    return low if low == high else f"{low}{sep}{high}"


def slashed(values, digits: int = 0) -> str:
    return " / ".join(f"{v:.{digits}f}" for v in values)


def thousands(value: float) -> str:
    return f"{value:,.0f}"


def ksteps(value: float | None) -> str:
    return "-" if value is None else f"{value / 1000:.0f}k"


def seconds(value: float) -> str:
    return f"{value:.0f} s" if value >= 10 else f"{value:.1f} s"


# ------------------------------------------------------------------------------------------------ intervals
@functools.cache
def mean_estimate(values: tuple[float, ...]) -> Estimate:
    """The mean over seeds with its 95 % stratified-bootstrap interval (each score set bootstrapped once)."""
    return aggregate({"x": np.asarray(values, float).reshape(-1, 1)})["x"]["mean"]


@functools.cache
def improvement_estimate(x: tuple[float, ...], y: tuple[float, ...]) -> Estimate:
    """P(a run of x ends above a run of y) with its 95 % interval."""
    return improvement(np.asarray(x, float).reshape(-1, 1), np.asarray(y, float).reshape(-1, 1))


def interval_cell(values: list[float]) -> str:
    """Mean [95 % interval] (each seed's value)."""
    return f"{mean_estimate(tuple(values)).text()} ({', '.join(f'{v:.0f}' for v in values)})"


# ------------------------------------------------------------------------------------------------ GridWorld
def keep(runs: Path) -> None:
    for name, _ in ROWS:
        for file in FILES:
            if (runs / name / file).exists():
                (KEPT / name).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(runs / name / file, KEPT / name / file)
    if (runs / "data" / "metadata.json").exists():
        (KEPT / "data").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(runs / "data" / "metadata.json", KEPT / "data" / "metadata.json")
    if (runs / "clone_gauss" / "model_0.pt").exists():
        rows = timeout_rows(runs / "clone_gauss")
        TIMEOUTS.write_text(json.dumps({str(y): k for y, k in sorted(rows.items())}, indent=2) + "\n")


def timeout_rows(run: Path, episodes: int = 200) -> Counter:
    """Where the Gaussian clone's time-outs stand: the row (y) of each episode the time-out ended."""
    import torch

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    resolved = load_run(run, {"device": "cpu"})
    cfg = resolved.cfg
    env = make_env(resolved.task, num_envs=episodes, device="cpu", seed=cfg["seed"] + 10_000, **cfg["env"])
    _, runner = build_runner(resolved, None, env=env)
    load_latest(runner, run, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device="cpu")
    rows: Counter[int] = Counter()
    obs, ended = env.reset(), torch.zeros(episodes, dtype=torch.bool)
    with torch.inference_mode():
        for _ in range(int(env.max_episode_length)):
            before = env.positions.clone()
            obs, _, dones, extras = env.step(actor(obs))
            timed_out = extras["time_outs"] & ~ended
            for i in timed_out.nonzero().flatten().tolist():
                rows[int(before[i, 1])] += 1
            ended |= dones
            if bool(ended.all()):
                break
    return rows


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


def _yaml(path: Path) -> dict:
    return yaml.safe_load(path.read_text())


def _settings(results: dict) -> list[tuple[str, str]]:
    """(eval.json key, the table's N) of the settings the table shows."""
    return [(s, s[2:] if s.startswith("N=") else "mean action") for s in ("N=1", "N=10", "mean_action") if s in results]


def unshown_settings(results: dict[str, dict]) -> list[str]:
    """The evaluation settings in the runs' eval.json that the table leaves out."""
    shown = {s for r in results.values() for s, _ in _settings(r)}
    return sorted({s for r in results.values() for s in r} - shown)


def gridworld_table() -> str:
    lines = ["| policy | N | success | top share | bottom share | episode length |", "|---|---|---|---|---|---|"]
    d = _json(KEPT / "clone_flow" / "eval.json")["dataset"]
    lines.append(
        f"| demonstrations (scripted, {d['episodes']:,} episodes) | - | {d['success_rate']:.3f} | "
        f"{d['top_share']:.3f} | {d['bottom_share']:.3f} | {d['length_mean']:.2f} |"
    )
    for name, what in ROWS:
        results = _json(KEPT / name / "eval.json")["results"]
        for setting, n in _settings(results):
            r = results[setting]
            lines.append(
                f"| {what} | {n} | {r['success_rate']:.3f} | {r['top_share']:.3f} | "
                f"{r['bottom_share']:.3f} | {r['length_mean']:.1f} |"
            )
    return "\n".join(lines)


def gridworld_values() -> dict:
    from refpo_warp.tasks.gridworld.cfg import GridWorldCfg

    evals = {name: _json(KEPT / name / "eval.json") for name, _ in ROWS}
    configs = {name: _yaml(KEPT / name / "config.yaml") for name, _ in ROWS}
    meta = _json(KEPT / "data" / "metadata.json")["refpo"]
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
        rows = {int(y): k for y, k in _json(TIMEOUTS).items()}
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
        "gw_episodes": f"{_json(KEPT / 'data' / 'metadata.json')['total_episodes']:,}",
        "gw_steps": f"{_json(KEPT / 'data' / 'metadata.json')['total_steps']:,}",
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
            f"{words([s.replace('=', ' = ') for s in unshown])} also in the eval.json of "
            + ("every flow run" if set(with_unshown) == {n for n in res if "N=10" in res[n]} else words(with_unshown))
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
    return f"seeds {seeds_text(twice)} recorded more than once, with {words(threads)} torch threads" + (
        ", alike in these statistics" if alike else ", differing in these statistics"
    )


def learning_check_values() -> dict:
    """The learning check's records: each run's statistics as tests/learning/checks.py computes them."""
    records = [json.loads(line) for line in CHECK_RECORDS.read_text().splitlines() if line.strip()]
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


# ------------------------------------------------------------------------------------------------ DMC: the runs
@dataclass(frozen=True)
class Run:
    path: Path
    seed: int
    n10: float  # the final evaluation: N = 10, or PPO's mean action
    n1: float | None
    rows: tuple
    train_time_s: float

    @property
    def curve(self) -> tuple[list[float], list[float]]:
        """(env steps, return) of the periodic evaluations: N = 10 for a flow, the mean action for PPO."""
        key = "eval/return_N10" if any("eval/return_N10" in r for r in self.rows) else "eval/return"
        points = [(r["env_steps"], r[key]) for r in self.rows if key in r]
        return [p[0] for p in points], [p[1] for p in points]

    @property
    def peak(self) -> tuple[float, int]:
        """(the highest periodic N = 10 return, its iteration)."""
        key = "eval/return_N10" if any("eval/return_N10" in r for r in self.rows) else "eval/return"
        return max((r[key], r["iteration"]) for r in self.rows if key in r)

    @property
    def last_periodic(self) -> float:
        return self.curve[1][-1]

    @property
    def fell(self) -> bool:
        return self.last_periodic < FALL * self.peak[0]

    def at(self, key: str, iteration: int | None = None) -> float:
        """A progress scalar at ``iteration`` (the last row when None)."""
        row = self.rows[-1] if iteration is None else next(r for r in self.rows if r["iteration"] == iteration)
        return row[key]


def _final(path: Path) -> tuple[float, float | None]:
    """(N = 10 or the Gaussian's mean-action return, N = 1 return or None) of an eval.json."""
    results = _json(path)["results"]
    if "mean_action" in results:
        return results["mean_action"]["return_mean"], None
    return results["N=10"]["return_mean"], results["N=1"]["return_mean"]


@functools.cache
def load_run(path: Path) -> Run:
    from refpo_warp.runner.progress import read_rows

    evaluation = _json(path / "eval.json")
    n10, n1 = _final(path / "eval.json")
    return Run(path, evaluation["seed"], n10, n1, tuple(read_rows(path)), evaluation["train_time_s"])


@functools.cache
def group(kept: Path, task: str, label: str) -> tuple[Run, ...]:
    return tuple(
        sorted((load_run(p.parent) for p in (kept / task / label).glob("seed*/eval.json")), key=lambda r: r.seed)
    )


def n10(runs, seeds=None) -> list[float]:
    return [r.n10 for r in runs if seeds is None or r.seed in seeds]


def _curve(run: Path) -> tuple[list[float], list[float]]:
    return load_run(run).curve


def first_reaching(curve: tuple[list[float], list[float]], value: float) -> float | None:
    """Env steps at the first periodic evaluation of ``curve`` whose return reaches ``value``."""
    return next((s for s, v in zip(*curve) if v >= value), None)


def keep_dmc(runs: Path, sweeps: Path) -> None:
    """The DMC study's small files (each stage's and each finished run's config, eval.json and progress rows), from
    runs/finetuning/dmc and the sweeps of DMC_SOURCES into their folders here."""
    for task in DMC_TASKS:
        stages = [(runs / task / name, DMC_KEPT / task / name) for name in ("demonstrator", "clone_refpo", "clone_ppo")]
        for kept, names, _ in DMC_SOURCES:
            for name in names:
                stages += [
                    (run, kept / task / run.parent.name / run.name)
                    for run in sorted((sweeps / name.format(task[4:]) / task).glob("*/seed*"))
                ]
        for src, dst in stages:
            if (src / "eval.json").exists():
                dst.mkdir(parents=True, exist_ok=True)
                for file in FILES:
                    if (src / file).exists():
                        shutil.copyfile(src / file, dst / file)
        if (runs / task / "data" / "metadata.json").exists():
            (DMC_KEPT / task / "data").mkdir(parents=True, exist_ok=True)
            shutil.copyfile(runs / task / "data" / "metadata.json", DMC_KEPT / task / "data" / "metadata.json")


def _groups(task: str) -> Iterator[tuple[str, str, str, str, list[Path]]]:
    """(start, label, base, what, seed runs) of the task's fine-tuned and from-scratch groups, in the table's order:
    per method, its runs from the clone, with the normalisers updated, its variants, from scratch."""
    for label, base, what in DMC_METHODS:
        clone = "Gaussian clone" if base == "ppo" else "flow clone"
        for kept, _, start in DMC_SOURCES:
            runs = sorted((kept / task / label).glob("seed*/eval.json"))
            if runs:
                yield start.format(clone=clone), label, base, what, [r.parent for r in runs]


@functools.cache
def _cpu_dmc() -> dict[tuple[str, str], dict]:
    """The committed cpu_dmc rows by (task, label)."""
    with FROM_SCRATCH.open() as f:
        return {(r["task"], r["label"]): r for r in csv.DictReader(f)}


def _targets(task: str) -> tuple[float, float]:
    """The data's return and PPO's from-scratch final return at the full CPU profile (cpu_dmc)."""
    data = _json(DMC_KEPT / task / "clone_refpo" / "eval.json")["dataset"]["return_mean"]
    return data, float(_cpu_dmc()[(task, "ppo")]["return_multi_mean"])


# ------------------------------------------------------------------------------------------------ DMC: the page
def demonstrator_facts(task: str) -> dict:
    root = DMC_KEPT / task
    cfg = _yaml(root / "demonstrator" / "config.yaml")
    evaluation = _json(root / "demonstrator" / "eval.json")
    run = load_run(root / "demonstrator")
    meta = _json(root / "data" / "metadata.json")
    policy = meta["refpo"]["policy"]
    data, ppo_final = _targets(task)
    target = round(ppo_final / 2)  # dmc.sh's TARGET: half of PPO's full-profile final
    evaluated = [(r["iteration"], r["eval/return"]) for r in run.rows if "eval/return" in r]
    crossing = next(i for i, (_, v) in enumerate(evaluated) if v >= target)
    rule = min(evaluated[: crossing + 1], key=lambda e: abs(e[1] - target))  # half_return_checkpoint.py's rule
    used = next(e for e in evaluated if e[0] == policy["iteration"])
    clones = {name: _json(root / name / "eval.json") for name in ("clone_refpo", "clone_ppo")}
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
        "profile_steps": math.ceil(_yaml(root / "demonstrator" / "config.yaml")["total_env_steps"] / per_iteration)
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
        meta = _json(root / "data" / "metadata.json")["refpo"]
        data, ppo_final = _targets(task)
        demo = Path(meta["policy"]["checkpoint"]).stem
        lines.append(
            f"| {task} | demonstrations: PPO's {demo}, mean action + noise {meta['policy']['action_noise_std']:g} "
            f"| {data:.0f} over the dataset's episodes | | | |"
        )
        for name, what in (("clone_refpo", "flow clone (0 env steps)"), ("clone_ppo", "Gaussian clone (0 env steps)")):
            multi, one = _final(root / name / "eval.json")
            lines.append(f"| {task} | {what} | {multi:.0f} | {'-' if one is None else f'{one:.0f}'} | | |")
        for start, _, _, what, dirs in _groups(task):
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
    chosen = tuple(sorted(_yaml(HERE / "remedies.yaml")["seeds"]))
    held = {r.seed for label in FLOWS_HELD + ("ppo",) for r in group(DMC_KEPT, task, label)}
    return chosen, tuple(sorted(held - set(chosen)))


def versus_scratch(task: str, label: str) -> tuple[tuple[Run, ...], tuple[Run, ...], Estimate]:
    fine, scratch = group(DMC_KEPT, task, label), group(SCRATCH_KEPT, task, label)
    return fine, scratch, improvement_estimate(tuple(n10(fine)), tuple(n10(scratch)))


def verdict(p: Estimate, better: str, worse: str) -> str:
    if p.low > 0.5:
        return f"{better} above"
    if p.high < 0.5:
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
            if p.low > 0.5:
                separated.append(name)
            else:
                not_separated.append(
                    f"{name} (P = {p.point:.2f}; from scratch its seeds end at {slashed(n10(scratch))})"
                )
    sentence = (
        f"The interval puts fine-tuning above starting from scratch for {words(separated) if separated else 'none'}"
    )
    sentence += f"; it holds one half, separating nothing, for {words(not_separated)}." if not_separated else "."
    return {"scratch_table": "\n".join(lines), "scratch_sentence": sentence}


def reach_sentence() -> str:
    """Which runs reach the data's return and PPO's full-profile final, and when."""
    parts, full = [], []
    for task in DMC_TASKS:
        data, ppo_final = _targets(task)
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
            listed = "; ".join(f"{c} seeds of {words(m)}" for c, m in counts.items())
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
                p = improvement_estimate(tuple(n10(runs)), tuple(n10(ppo_runs)))
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
        p = improvement_estimate(tuple(values), tuple(ppo_fresh))
        item = f"{prose(label)} ({span(values)})"
        (beaten if max(values) < min(ppo_fresh) else above if p.low > 0.5 else split).append(item)
    text = (
        f"On point_mass's fresh seeds {seeds_text(fresh)} (run after adaptive λ and ASPO were chosen on seeds "
        f"{seeds_text(chosen)}, which the all-seed rows pool with them) every PPO seed ({span(ppo_fresh)}) ends above "
        f"every seed of {words(beaten) if beaten else 'no method'}"
    )
    if split:
        text += f"; the seeds of {words(split)} mix with PPO's"
    if above:
        text += f"; {words(above)} ends above PPO"
    sentences.append(text + ".")
    task = "dmc_reacher_easy"
    reacher_ppo = n10(group(DMC_KEPT, task, "ppo"))
    rest = []
    for label in FLOWS_HELD:
        reacher_runs = group(DMC_KEPT, task, label)
        if reacher_runs:
            p = improvement_estimate(tuple(n10(reacher_runs)), tuple(reacher_ppo))
            rest.append((prose(label), p))
    none = all(not p.separates for _, p in rest)
    sentences.append(
        f"On reacher_easy ({len(reacher_ppo)} seeds each) "
        + (
            f"no interval separates a flow method from PPO (P = {span([p.point for _, p in rest], 2)})."
            if none
            else "the intervals separate "
            + words([f"{n} ({p.text(2)})" for n, p in rest if p.separates])
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
        w = _yaml(runs[0].path / "config.yaml")["critic_warmup_iterations"]
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
    clone = _final(DMC_KEPT / task / "clone_refpo" / "eval.json")[0]

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
            + words(
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
            p = improvement_estimate(tuple(n10(held)), tuple(n10(updated)))
            lines.append(
                f"| {task} | {NAMES[label]} | {interval_cell(n10(held))} | {interval_cell(n10(updated))} | "
                f"{p.text(2)} | {verdict(p, 'held', 'updated')} |"
            )
            verdicts[(task, label)] = p
    pm = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_point_mass" and p.low > 0.5]
    pm_not = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_point_mass" and not p.low > 0.5]
    re_sep = [prose(m) for (t, m), p in verdicts.items() if t == "dmc_reacher_easy" and p.separates]
    sentence = (
        "On point_mass the interval puts the held normalisers above the updated ones for "
        f"{words(pm) if pm else 'no method'}"
        + (f", not for {words(pm_not)}" if pm_not else "")
        + "; on reacher_easy "
        + (f"it separates {words(re_sep)}." if re_sep else "it separates no method.")
    )
    return {"held_table": "\n".join(lines), "held_sentence": sentence}


def _reflow_schedule():
    """refpo_warp/algorithms/reflow_schedule.py, loaded on its own: the package's __init__ would import torch."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("reflow_schedule", ROOT / "refpo_warp/algorithms/reflow_schedule.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def adaptive_values() -> dict:
    """Where adaptive λ sat (``Flow/reflow_coef`` in every adaptive run's progress rows), the fresh seeds' comparisons
    and the section's conclusion."""
    module = _reflow_schedule()
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
        f"; it reached its upper bound {high} in {len(reached)} of {len(runs)} adaptive runs ({words(sources)})"
        + (f", at iteration {span(reached)}" if reached else "")
        + f", and stayed there to the last update in {stayed} of {len(runs)}; the ratio ended at "
        f"{span(end_ratio, 1)}."
    )
    if stayed == len(runs) and reached:
        text += f" In effect these runs are a fixed λ = {high} from iteration {span(reached)} on."
    if schedule.high not in fixed:
        text += (
            f" None of the fixed-λ runs on this page uses λ = {high} (they use "
            f"{words(sorted(f'{v:g}' for v in fixed))}), so these runs do not tell the schedule from the larger λ."
        )

    task = "dmc_point_mass"
    chosen, fresh = chosen_and_fresh(task)
    adaptive = n10(group(DMC_KEPT, task, "refpo_adaptive"), fresh)
    aspo = n10(group(DMC_KEPT, task, "refpo_aspo"), fresh)
    plain = n10(group(DMC_KEPT, task, "refpo"), fresh)
    ppo = n10(group(DMC_KEPT, task, "ppo"), fresh)
    p_plain = improvement_estimate(tuple(adaptive), tuple(plain))
    p_ppo = improvement_estimate(tuple(adaptive), tuple(ppo))
    p_aspo_ppo = improvement_estimate(tuple(aspo), tuple(ppo))
    reacher = n10(group(DMC_KEPT, "dmc_reacher_easy", "refpo_adaptive"))
    reacher_plain = n10(group(DMC_KEPT, "dmc_reacher_easy", "refpo"))
    p_reacher = improvement_estimate(tuple(reacher), tuple(reacher_plain))

    def separated(p: Estimate) -> str:
        return "the interval separates them" if p.separates else "the interval holds one half: not separated"

    def against(p: Estimate, name: str, other: str) -> str:
        if p.low > 0.5:
            return f"{name} ends above {other}"
        if p.high < 0.5:
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
            f"starting from {words(sorted(f'{v:g}' for v in starts))}"
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


PAIRS = [(task, label) for task in DMC_TASKS for label, _, _ in DMC_METHODS]


def dmc_values() -> dict:
    facts = {task: demonstrator_facts(task) for task in DMC_TASKS}
    first = facts[DMC_TASKS[0]]
    fine = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(DMC_KEPT, task, label)]
    updated = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(UPDATED_KEPT, task, label)]
    scratch = [r for task in DMC_TASKS for label, _, _ in DMC_METHODS for r in group(SCRATCH_KEPT, task, label)]
    steps = {_json(r.path / "eval.json")["env_steps"] for r in fine + updated + scratch}
    (ft_steps,) = steps
    evaluations = {result["episodes"] for r in fine for result in _json(r.path / "eval.json")["results"].values()}
    periodic = Counter(b - a for r in fine for a, b in zip(r.curve[0], r.curve[0][1:]))
    interval_steps = periodic.most_common(1)[0][0]
    seeds_counts = sorted({len(group(k, t, m)) for k in (DMC_KEPT, SCRATCH_KEPT) for t, m in PAIRS} - {0})
    ratio_words, below = [], []
    for task, f in facts.items():
        r = f["data"] / f["ppo_final"]
        ratio_words.append(f"{r:.2f} on {task[4:]}")
        below += [task[4:]] if r < 0.5 else []
    weaker = all(f["data"] < f["ppo_final"] for f in facts.values())
    data_ratios = (
        f"The data's return over PPO's full-profile final is {words(ratio_words)}: "
        + ("below PPO's final on every task" if weaker else "not below PPO's final on every task")
        + (
            f", below the half the study aimed for on {words(below)} only."
            if below and len(below) < len(facts)
            else f", below the half the study aimed for on {'every task' if below else 'no task'}."
        )
    )
    gap = [
        f"{task[4:]}'s checkpoint evaluated at {f['used'][1]:.0f} ({f['periodic_episodes']} episodes) and its "
        f"{f['episodes']} collected episodes average {f['data']:.0f}"
        for task, f in facts.items()
    ]
    rule_differs = [task for task, f in facts.items() if f["rule"][0] != f["used"][0]]
    if rule_differs:
        rule = (
            "; ".join(
                f"On {t[4:]} the data come from iteration {facts[t]['used'][0]} ({facts[t]['used'][1]:.0f}), not from "
                f"iteration {facts[t]['rule'][0]} ({facts[t]['rule'][1]:.0f})"
                for t in rule_differs
            )
            + ", the checkpoint `half_return_checkpoint.py` picks from the committed progress rows (the evaluated "
            "checkpoint nearest the target up to the first evaluation that reaches it)."
        )
    else:
        rule = "Each task's data come from the checkpoint `half_return_checkpoint.py` picks from the committed rows."

    def minutes(runs: list[Run]) -> str:
        return span([r.train_time_s / 60 for r in runs], 1)

    return {
        "demonstrator_table": demonstrator_table(facts),
        "dmc_episodes": seeds_text({f["episodes"] for f in facts.values()}),
        "dmc_noise": words(sorted({f"{f['noise']:g}" for f in facts.values()})),
        "data_ratios": data_ratios,
        "data_gap": "; ".join(gap),
        "rule_sentence": rule,
        "ft_steps": thousands(ft_steps),
        "ft_share": f"{ft_steps / first['profile_steps']:.2f}",
        "profile_steps": thousands(first["profile_steps"]),
        "ft_minutes": minutes(fine),
        "updated_minutes": minutes(updated),
        "scratch_minutes": minutes(scratch),
        "final_episodes": seeds_text(evaluations),
        "seed_counts": " or ".join(str(n) for n in seeds_counts),
        "periodic_steps": thousands(interval_steps),
        "periodic_episodes": seeds_text({_yaml(r.path / "config.yaml")["eval"]["interval_num_envs"] for r in fine}),
        "ppo_full": " / ".join(f"{f['ppo_final']:.0f}" for f in facts.values()),
        "ppo_full_runs": words(sorted({_cpu_dmc()[(t, "ppo")]["return_multi_n"] for t in DMC_TASKS})),
        "dmc_table": dmc_table(),
        "reach_sentence": reach_sentence(),
        "one_step_sentence": one_step_sentence(),
        "pm_seeds_held": seeds_text(r.seed for r in group(DMC_KEPT, "dmc_point_mass", "refpo")),
        **scratch_values(),
        **ppo_values(),
        **collapse_values(),
        **held_values(),
        **adaptive_values(),
    }


# ------------------------------------------------------------------------------------------------ figures
def dmc_curves(path: Path, remedies: bool = False) -> Path | None:
    """The periodic evaluation return over env steps, seeds' mean with their range shaded, the data's return and
    PPO's full-profile final as dotted lines. One panel per (task, method): fine-tuned from the clone (solid) beside
    from scratch (dashed); with ``remedies``, one panel per task with a variant, ReFPO's fine-tuning beside each
    variant tried against its collapse."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    from refpo_warp.evaluation.curves import seed_stats
    from refpo_warp.utils.atomic_files import save_figure

    names = {label: what for label, _, what in DMC_METHODS}
    if remedies:
        tried = [(task, [g for g in _groups(task) if g[0] != "scratch" and g[2] == "refpo"]) for task in DMC_TASKS]
        panels = [
            (task, groups, "ReFPO from the flow clone, remedies tried") for task, groups in tried if len(groups) > 1
        ]
    else:
        panels = [
            (task, [g for g in _groups(task) if g[1] == base], names[base])
            for task in DMC_TASKS
            for base in ("refpo", "refpo_onestep", "ppo")
        ]
    if not panels:
        return None
    cols = 1 if remedies else 3
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.4 * cols * (2.0 if remedies else 1), 3.3 * rows), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (task, groups, title) in zip(axes.flat, panels):
        data, ppo_final = _targets(task)
        for i, (start, _, base, what, runs) in enumerate(groups):
            curves = [_curve(run) for run in runs]
            if start != "scratch":  # the clone's own evaluation at 0 env steps starts the curve
                first = _final(DMC_KEPT / task / ("clone_ppo" if base == "ppo" else "clone_refpo") / "eval.json")[0]
                curves = [([0, *x], [first, *y]) for x, y in curves]
            steps, mean, low, high = seed_stats(curves)
            color = "0.35" if start == "scratch" else colors[i % len(colors)]
            name = f"{what}, from {start}" if remedies or start == "scratch" else f"from {start}"
            ax.plot(steps, mean, color=color, ls="--" if start == "scratch" else "-", lw=1.6, label=name)
            ax.fill_between(steps, low, high, color=color, alpha=0.1, lw=0)
        ax.axhline(data, color="tab:green", ls=":", lw=1, label="the data's return")
        ax.axhline(ppo_final, color="black", ls=":", lw=1, label="PPO from scratch, full profile")
        ax.set_title(f"{task}: {title}", fontsize=9)
        ax.set_xlabel("env steps")
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda x, _: f"{x / 1000:.0f}k"))
        ax.set_ylim(0, 1000)
        ax.grid(alpha=0.3)
        if remedies:  # many lines: the legend beside the panel
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        else:
            ax.legend(fontsize=6.5, loc="best")
    for ax in axes.flat[len(panels) :]:
        ax.set_visible(False)
    axes[0, 0].set_ylabel("return (N = 10; PPO: mean action)")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------------ the page
def page_values() -> dict:
    return {**gridworld_values(), **learning_check_values(), **dmc_values()}


def main() -> None:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args(__doc__)
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--runs", type=Path, default=Path("runs/finetuning/gridworld"), help="the GridWorld runs")
    parser.add_argument("--keep", action="store_true", help="copy the GridWorld runs' small files here first")
    parser.add_argument("--dmc", action="store_true", help="copy the DMC runs' small files here first; the figures")
    args = parser.parse_args()
    if args.check and (args.keep or args.dmc):
        parser.error("--check reads the committed files only: give it alone")
    if args.keep:
        keep(args.runs)
    if args.dmc:
        keep_dmc(Path("runs/finetuning/dmc"), Path("runs/sweeps"))
        print(dmc_curves(DMC_FIGURE), dmc_curves(REMEDIES_FIGURE, remedies=True))
    same = write_page(TEMPLATE, page_values(), check=args.check)
    if args.check and not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
