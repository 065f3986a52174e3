"""The bounded learning checks: what each trains, the statistic it reads and the bound that statistic must meet.

A check trains one method on one task with a profile that ships in ``configs/`` and reads one or more statistics
from the run: the final evaluation against the policy the run started from (same seed and construction, the run's
own evaluation protocol, measured in the same test), or the trend of a training curve. Its **null control** is the
same check with learning switched off (``NULL_CONTROL``: a learning rate of 1e-12 and a fixed schedule, nothing else
changed); a check's bound must fail there. ``docs/results/learning_checks.md`` gives each check's measured runs
(seeds 1-5 on one torch thread, 1-3 on two, the null control on seeds 1-3) and where its bound sits between them;
``tests/learning/measure.py`` makes those runs and that table.

CI's default test command runs seven of them: ReFPO on GridWorld (N = 1 and 10), on the humanoid and on mjlab's
cartpole (in the mjlab job), ReFPO's one-step configuration on point_mass (a whole 1M-step profile), ReinFlow on
GridWorld, ReFPO fine-tuning a flow clone of GridWorld demonstrations, and the flow clone of the two-way task's
demonstrations taking both ways. The DMC cartpole's five run on demand
(``--all-checks``; ``in_ci=False``), to keep CI's whole run within
its 25 minutes: ReFPO, Gaussian PPO, the advantage-weighted ReFPO, FPO++ and Flow-GRPO (the first four share ReFPO's
or rsl_rl's update loop, and each loss term of their own has hand-worked unit tests).

A bound obeys the rule the table checks: strictly beyond the null control's best, and at most halfway from it to the
learning runs' worst, so that another CPU, which moves a run as another seed does, cannot fail it by a hair. A claim
bound (``Bound.claim``) is what a method promises rather than a place between the runs: every learning run meets it,
and beside it the check has a bound of the first kind for the null control to fail.
"""

from __future__ import annotations

import contextlib
import io
import operator
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

NULL_CONTROL = ("algorithm.learning_rate=1e-12", "algorithm.schedule=fixed")
ROW_KEYS = ("iteration", "env_steps", "reward_mean", "episode_length_mean")  # kept per iteration in a record


@dataclass(frozen=True)
class Bound:
    """``statistic op value``: ``>=`` (higher is learning) or ``<=`` (lower is learning). A ``claim`` bound is the
    value a method promises (one-step return at least 0.9 x ten-step), not one placed between the runs: every
    learning run must meet it, and the null control may meet it alone, so its check needs another bound the null
    control fails."""

    statistic: str
    op: str
    value: float
    claim: bool = False

    def holds(self, stats: dict[str, float]) -> bool:
        return {">=": operator.ge, "<=": operator.le}[self.op](stats[self.statistic], self.value)

    def __str__(self) -> str:
        return f"{self.statistic} {self.op} {self.value:g}"


@dataclass(frozen=True)
class LearningCheck:
    """One learning check: ``overrides`` (without seed, device and run dir) train it, ``statistics(record)`` reads
    it, every bound in ``bounds`` must hold; ``initial_eval`` evaluates the starting policy first."""

    name: str
    overrides: tuple[str, ...]
    statistics: Callable[[dict], dict[str, float]]
    bounds: tuple[Bound, ...]
    initial_eval: bool = True
    describe: str = ""
    properties: Callable[[dict], list[str]] = field(default=lambda record: [])  # failures of non-learning asserts
    runner: str = "refpo_warp"  # or "mjlab": mjlab's own train command, in an mjlab environment; or "finetune":
    # refpo_warp's, from a clone of demonstrations (run_finetune_check)
    minutes: float = 3.0  # its wall time in CI (the slow marker's, which orders the run), from a fresh-clone run's
    # pytest --durations
    in_ci: bool = True  # run by the default test command (CI's); False: on demand with --all-checks

    def verdict(self, record: dict) -> tuple[bool, dict[str, float]]:
        stats = self.statistics(record)
        return all(b.holds(stats) for b in self.bounds), stats


# ------------------------------------------------------------------------------------------------------ statistics
def gain(record: dict, setting: str, key: str = "return_mean") -> float:
    """Final evaluation over the initial policy's, for one evaluation setting (``N=10``, ``mean_action``)."""
    return record["final"][setting][key] / record["initial"][setting][key]


def linear_trend(y) -> tuple[float, float]:
    """(t statistic of the least-squares slope, fitted rise over the series relative to the fitted start)."""
    y = np.asarray(y, dtype=float)
    x = np.arange(len(y), dtype=float)
    slope, start = np.polyfit(x, y, 1)
    residuals = y - (start + slope * x)
    standard_error = np.sqrt(residuals @ residuals / (len(y) - 2) / ((x - x.mean()) ** 2).sum())
    return float(slope / standard_error), float(slope * (len(y) - 1) / start)


def return_gains(*settings: str):
    def statistics(record: dict) -> dict[str, float]:
        return {f"gain_{s}": gain(record, s) for s in settings}

    return statistics


def mean_gain(*settings: str):
    """The mean of the gains over several evaluation settings: one statistic from more episodes, for a method whose
    gain is small beside the evaluation's noise."""

    def statistics(record: dict) -> dict[str, float]:
        return {"mean_gain": float(np.mean([gain(record, s) for s in settings]))}

    return statistics


def one_step_holds(record: dict) -> dict[str, float]:
    """The N = 10 return's rise over the initial policy's, and the deployed N = 1 return over the N = 10 one (0 when
    the N = 10 return is not positive: nothing deployed to keep)."""
    n10, n1 = (record["final"][s]["return_mean"] for s in ("N=10", "N=1"))
    return {"rise_N=10": n10 - record["initial"]["N=10"]["return_mean"], "ratio_N=1/N=10": n1 / n10 if n10 > 0 else 0.0}


def length_ratios(*settings: str):
    """Episode length relative to the initial policy's, per setting (a learned GridWorld policy walks straight to a
    goal band)."""

    def statistics(record: dict) -> dict[str, float]:
        return {
            f"length_ratio_{s}": record["final"][s]["length_mean"] / record["initial"][s]["length_mean"]
            for s in settings
        }

    return statistics


def gridworld_properties(record: dict) -> list[str]:
    """The paper's multimodality: both goal bands keep a real share of the successes; no ratio explosions."""
    failures = [
        f"{s}: {record['final'][s]}"
        for s in ("N=1", "N=10")
        if min(record["final"][s]["top_share"], record["final"][s]["bottom_share"]) < 0.2
    ]
    if record["diagnostics"].get("explosion_rate", 0.0) >= 0.01:
        failures.append(f"explosion_rate {record['diagnostics']['explosion_rate']}")
    return failures


def finetuning_gains(record: dict) -> dict[str, float]:
    """Fine-tuning from a clone: the episode length at N = 1 and 10 relative to the clone's (the clone's flow wanders,
    most at N = 1; the fine-tuned one walks to a band), and, unbounded, the change of the data's minority band's
    (bottom) share at N = 10."""
    final, initial = record["final"], record["initial"]
    out = {f"length_ratio_{s}": final[s]["length_mean"] / initial[s]["length_mean"] for s in ("N=1", "N=10")}
    out["bottom_share_change_N=10"] = final["N=10"]["bottom_share"] - initial["N=10"]["bottom_share"]
    return out


def both_bands_kept(record: dict) -> list[str]:
    """Fine-tuning keeps the demonstrations' two modes: each goal band keeps a real share of the successes."""
    return [
        f"{s}: {record['final'][s]}"
        for s in ("N=1", "N=10")
        if min(record["final"][s]["top_share"], record["final"][s]["bottom_share"]) < 0.2
    ]


def ways_kept(record: dict) -> dict[str, float]:
    """Cloning two ways: the flow clone's rarer way at N = 10 (the smaller of its left and right shares of the
    episodes), and, unbounded, the Gaussian clone's (its mean action) and the two clones' success. A Gaussian clone
    takes one way (or averages them into the wall); it may still succeed, by the data's more frequent way."""
    flow, gauss = record["final"]["N=10"], record["initial"]["mean_action"]
    return {
        "minority_way_N=10": min(flow["went_left_mean"], flow["went_right_mean"]),
        "gaussian_minority_way": min(gauss["went_left_mean"], gauss["went_right_mean"]),
        "success_N=10": flow["success_mean"],
        "gaussian_success": gauss["success_mean"],
    }


def length_trend(record: dict) -> dict[str, float]:
    t, rise = linear_trend([row["episode_length_mean"] for row in record["rows"]])
    return {"length_trend_t": t, "length_rise": rise}


def rate_gain(record: dict) -> dict[str, float]:
    """mjlab: the last checkpoint's deterministic return rate minus the first checkpoint's."""
    return {"rate_gain": record["final"]["reward_rate"] - record["initial"]["reward_rate"]}


# ------------------------------------------------------------------------------------------------------ the checks
CARTPOLE = ("task=dmc_cartpole_balance",)
# The fine-tuning check's clone: GridWorld's scripted demonstrator (top 0.63 / bottom 0.37 of its episodes), cloned by
# refpo pretrain; each seed collects and clones its own (the clone is the policy its fine-tuning starts from).
FINETUNE_COLLECT = ("episodes=500", "num_envs=64")
FINETUNE_PRETRAIN = ("pretrain.epochs=30", "pretrain.num_pairs=8")
# The two-way clone check: the wall task's scripted demonstrator (60 / 40 left / right), cloned by refpo pretrain
# into ReFPO's flow actor and PPO's Gaussian one; each seed collects and clones its own.
# The clones are evaluated on 500-step episodes (the demonstrator is at the target after about 360 steps).
WAYS_COLLECT = ("task=dmc_point_mass_wall", "episodes=32", "num_envs=32", "demonstrator.left_share=0.6")
WAYS_PRETRAIN = (
    "pretrain.epochs=30",
    "pretrain.batch_size=512",
    "pretrain.num_pairs=8",
    "eval.num_envs=64",
    "eval.flow_steps=[10]",
    "env.max_episode_length=500",
)
MJLAB_ITERATIONS = 100
FPO_PP_OWN_VALUES = (
    "algorithm.learning_rate=0.0001",
    "algorithm.clip_param=0.05",
    "algorithm.num_learning_epochs=16",
    "actor.output_scale=1.0",
    "actor.action_noise_std=0.02",
)
CHECKS: dict[str, LearningCheck] = {
    check.name: check
    for check in (
        LearningCheck(
            "gridworld_refpo",
            ("task=gridworld", "algo=refpo", "eval.flow_steps=[1, 10]"),
            length_ratios("N=1", "N=10"),
            (Bound("length_ratio_N=1", "<=", 0.6), Bound("length_ratio_N=10", "<=", 0.6)),
            minutes=4.5,
            describe="ReFPO on GridWorld (the paper's 260k env steps): episode length at N = 1 and 10 over the "
            "initial policy's",
            properties=gridworld_properties,
        ),
        LearningCheck(
            "cartpole_refpo",
            (*CARTPOLE, "algo=refpo"),
            return_gains("N=10", "N=1"),
            (Bound("gain_N=10", ">=", 1.4), Bound("gain_N=1", ">=", 1.4)),
            minutes=4.9,
            in_ci=False,
            describe="ReFPO on dmc_cartpole_balance (450k env steps): N = 10 and N = 1 return over the initial "
            "policy's",
        ),
        LearningCheck(
            "cartpole_ppo",
            (*CARTPOLE, "algo=ppo", "eval.interval=0"),
            return_gains("mean_action"),
            (Bound("gain_mean_action", ">=", 1.5),),
            minutes=2.8,
            in_ci=False,
            describe="Gaussian PPO on dmc_cartpole_balance (450k env steps): mean-action return over the initial "
            "policy's",
        ),
        LearningCheck(
            "cartpole_refpo_aw",
            (*CARTPOLE, "algo=refpo_aw"),
            return_gains("N=10"),
            (Bound("gain_N=10", ">=", 1.5),),
            minutes=3.9,
            in_ci=False,
            describe="advantage-weighted ReFPO on dmc_cartpole_balance (450k env steps): N = 10 return over the "
            "initial policy's",
        ),
        LearningCheck(
            "cartpole_fpo_pp",
            # FPO++'s own values (configs/algo/fpo_pp.yaml), which the CPU profile replaced by tuned ones after the
            # check's bound was measured on them
            (*CARTPOLE, "algo=fpo_pp", *FPO_PP_OWN_VALUES),
            mean_gain("N=10", "N=1", "N=10/zero", "N=1/zero"),
            (Bound("mean_gain", ">=", 1.1),),
            minutes=4.3,
            in_ci=False,
            describe="FPO++ on dmc_cartpole_balance (450k env steps; the EMA actor): the mean of its N = 10 and N = 1 "
            "returns' gains over the initial policy's, from random and from zero initial noise",
        ),
        LearningCheck(
            "cartpole_flow_grpo",
            (*CARTPOLE, "algo=flow_grpo"),
            return_gains("N=10"),
            (Bound("gain_N=10", ">=", 1.2),),
            minutes=4.0,
            in_ci=False,
            describe="Flow-GRPO on dmc_cartpole_balance (1M env steps): N = 10 return over the initial policy's",
        ),
        LearningCheck(
            "point_mass_refpo_onestep",
            (
                "task=dmc_point_mass",
                "algo=refpo_onestep",
                "eval.interval=0",
                "eval.num_envs=64",
                "eval.initial_noise=[random]",
            ),
            one_step_holds,
            (Bound("rise_N=10", ">=", 250.0), Bound("ratio_N=1/N=10", ">=", 0.9, claim=True)),
            minutes=7.6,
            describe="ReFPO's one-step configuration on dmc_point_mass (the CPU profile's 1M env steps, past the "
            "540k-860k where the paper's ReFPO's N = 1 return collapses): N = 10 return's rise over the "
            "initial policy's, and N = 1 return over N = 10 return (64 episodes each)",
        ),
        LearningCheck(
            "gridworld_reinflow",
            ("task=gridworld", "algo=reinflow"),
            length_ratios("N=4", "N=1"),
            (Bound("length_ratio_N=4", "<=", 0.6),),
            minutes=2.3,
            describe="ReinFlow on GridWorld (the paper's 260k env steps): deterministic K = 4 chain's episode length "
            "over the initial policy's",
        ),
        LearningCheck(
            "gridworld_finetune_refpo",
            (
                "task=gridworld",
                "algo=refpo",
                "max_iterations=24",
                "critic_warmup_iterations=4",
                "eval.flow_steps=[1, 10]",
                "eval.interval=0",
            ),
            finetuning_gains,
            (Bound("length_ratio_N=1", "<=", 0.7), Bound("length_ratio_N=10", "<=", 0.9)),
            runner="finetune",
            minutes=1.2,
            properties=both_bands_kept,
            describe="ReFPO fine-tuned from a flow clone of GridWorld's scripted two-mode demonstrator (24 iterations, "
            "the first 4 the critic's warm-up): the episode length at N = 1 and 10 against the clone's; both "
            "goal bands keep a share",
        ),
        LearningCheck(
            "point_mass_wall_clones",
            ("task=dmc_point_mass_wall", "algo=refpo"),
            ways_kept,
            (Bound("minority_way_N=10", ">=", 0.05),),
            runner="clones",
            minutes=1.5,
            describe="Behaviour cloning of the two-way task's demonstrator (32 episodes, 30 epochs): the share of the "
            "flow clone's episodes at N = 10 that pass the wall by its rarer way",
        ),
        LearningCheck(
            "humanoid_refpo",
            ("task=humanoid_all_residual", "algo=refpo", "max_iterations=40", "eval.at_end=false"),
            length_trend,
            (Bound("length_trend_t", ">=", 3.0), Bound("length_rise", ">=", 0.05)),
            initial_eval=False,
            minutes=6.3,
            describe="ReFPO on humanoid_all_residual (40 iterations): trend of the training episode length",
        ),
        LearningCheck(
            "mjlab_cartpole_refpo",
            (
                "Mjlab-Cartpole-Balance-ReFPO",
                "--env.scene.num-envs",
                "64",
                "--agent.max-iterations",
                str(MJLAB_ITERATIONS),
            ),
            rate_gain,
            (Bound("rate_gain", ">=", 0.05),),
            runner="mjlab",
            minutes=3.6,
            describe=f"ReFPO inside mjlab's own train on Mjlab-Cartpole-Balance-ReFPO ({MJLAB_ITERATIONS} "
            "iterations, 64 envs): deterministic return rate of the last checkpoint minus the first's",
        ),
    )
}
MJLAB_NULL_CONTROL = ("--agent.algorithm.learning-rate", "1e-12")  # ReFPO's schedule is fixed already


# ------------------------------------------------------------------------------------------------------ running one
def overrides_of(check: LearningCheck, seed: int, run_dir: Path, null: bool) -> list[str]:
    return [*check.overrides, f"seed={seed}", "device=cpu", f"run_dir={run_dir}", *(NULL_CONTROL if null else ())]


def initial_results(overrides: list[str]) -> dict[str, dict]:
    """The final evaluation's results for the policy training with ``overrides`` starts from (same seed, same
    construction, the run's own evaluation protocol)."""
    from refpo_warp.config.resolve import resolve
    from refpo_warp.evaluation.evaluate_policy import evaluate_actor, make_eval_env
    from refpo_warp.runner.build import build_runner, seed_everything

    run = resolve(overrides)
    seed_everything(run.cfg["seed"])
    with contextlib.redirect_stdout(io.StringIO()):
        _, runner = build_runner(run, None)
    actor = runner.alg.get_policy().eval()
    results, _ = evaluate_actor(run, actor, make_eval_env(run), list(run.cfg["eval"]["flow_steps"]))
    return results


def run_mjlab_check(check: LearningCheck, seed: int, run_dir: Path, null: bool = False) -> dict:
    """mjlab's own ``train`` (the console script beside this interpreter) on the CPU with this process's torch threads,
    then the first and last checkpoints' deterministic return rate (``refpo_warp.integrations.mjlab.evaluate``)."""
    import os
    import subprocess
    import sys

    import torch

    from refpo_warp.integrations.mjlab.evaluate import evaluate

    task, *options = check.overrides
    cmd = [
        str(Path(sys.executable).parent / "train"),
        task,
        *options,
        "--agent.seed",
        str(seed),
        "--agent.logger",
        "tensorboard",
        "--gpu-ids",
        "None",
        "--log-root",
        str(run_dir),
        *(MJLAB_NULL_CONTROL if null else ()),
    ]
    env = {**os.environ, "OMP_NUM_THREADS": str(torch.get_num_threads())}
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=3600, check=False, env=env)
    if out.returncode:
        raise RuntimeError(f"mjlab's train failed ({out.returncode}):\n{out.stdout[-3000:]}{out.stderr[-3000:]}")
    (experiment,) = Path(run_dir).iterdir()
    (run,) = experiment.iterdir()
    last = max(run.glob("model_*.pt"), key=lambda p: int(p.stem.split("_")[1]))
    first, final = (evaluate(task, str(path)) for path in (run / "model_0.pt", last))
    return {
        "check": check.name,
        "overrides": list(check.overrides),
        "seed": seed,
        "null": null,
        "initial": first,
        "final": final,
        "diagnostics": {},
        "rows": [],
    }


def run_finetune_check(check: LearningCheck, seed: int, run_dir: Path, null: bool = False) -> dict:
    """Collect the scripted demonstrations and clone them (``FINETUNE_COLLECT``, ``FINETUNE_PRETRAIN``; seeded by
    ``seed``), then fine-tune the clone with the check's overrides; ``initial`` is the clone's evaluation in the same
    protocol. The null control switches the fine-tuning's learning off (the clone is what it starts from)."""
    from refpo_warp.demonstrations.collect import collect
    from refpo_warp.demonstrations.pretrain_run import pretrain
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.training import train

    run_dir = Path(run_dir)
    data, clone = run_dir.with_name(f"{run_dir.name}_data"), run_dir.with_name(f"{run_dir.name}_clone")
    task = next(o for o in check.overrides if o.startswith("task="))
    protocol = [o for o in check.overrides if o.startswith(("task=", "algo=", "eval.flow_steps="))]
    with contextlib.redirect_stdout(io.StringIO()):
        collect(
            {**parse_options([task, *FINETUNE_COLLECT]), "demonstrator": "scripted", "seed": seed, "out": str(data)}
        )
        cloned = pretrain(
            [*protocol, *FINETUNE_PRETRAIN, f"seed={seed}", "device=cpu", f"dataset={data}", f"run_dir={clone}"]
        )
    out = train([*overrides_of(check, seed, run_dir, null), f"init_from={clone}"])
    rows = [{k: row[k] for k in ROW_KEYS if k in row} for row in read_rows(run_dir)]
    return {
        "check": check.name,
        "overrides": list(check.overrides),
        "seed": seed,
        "null": null,
        "initial": cloned["results"],
        "final": out.get("results", {}),
        "diagnostics": out.get("diagnostics", {}),
        "rows": rows,
    }


def run_clones_check(check: LearningCheck, seed: int, run_dir: Path, null: bool = False) -> dict:
    """Collect the two-way task's scripted demonstrations (``WAYS_COLLECT``, seeded by ``seed``) and clone them twice
    (``WAYS_PRETRAIN``): ReFPO's flow actor (``final``) and PPO's Gaussian actor (``initial``). The null control
    switches the cloning's learning off (a learning rate of 1e-12: both clones stay as initialised)."""
    from refpo_warp.demonstrations.collect import collect
    from refpo_warp.demonstrations.pretrain_run import pretrain

    run_dir = Path(run_dir)
    data = run_dir.with_name(f"{run_dir.name}_data")
    off = ("pretrain.learning_rate=1e-12",) if null else ()
    common = [*WAYS_PRETRAIN, *off, f"seed={seed}", "device=cpu", f"dataset={data}"]
    with contextlib.redirect_stdout(io.StringIO()):
        collect({**parse_options(WAYS_COLLECT), "demonstrator": "scripted", "seed": seed, "out": str(data)})
        flow = pretrain([*check.overrides, *common, f"run_dir={run_dir}"])
        gauss = pretrain([WAYS_COLLECT[0], "algo=ppo", *common, f"run_dir={run_dir}_gauss"])
    return {
        "check": check.name,
        "overrides": list(check.overrides),
        "seed": seed,
        "null": null,
        "initial": gauss["results"],
        "final": flow["results"],
        "diagnostics": {},
        "rows": [],
    }


def parse_options(options) -> dict:
    from refpo_warp.config.dotted import parse_overrides

    return parse_overrides(list(options))


def run_check(check: LearningCheck, seed: int, run_dir: Path, null: bool = False) -> dict:
    """Train the check's run and return its record: initial and final evaluation, diagnostics, the training curve."""
    if check.runner == "mjlab":
        return run_mjlab_check(check, seed, run_dir, null)
    if check.runner == "finetune":
        return run_finetune_check(check, seed, run_dir, null)
    if check.runner == "clones":
        return run_clones_check(check, seed, run_dir, null)
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.training import train

    overrides = overrides_of(check, seed, Path(run_dir), null)
    initial = initial_results(overrides) if check.initial_eval else {}
    out = train(overrides)
    rows = [{k: row[k] for k in ROW_KEYS if k in row} for row in read_rows(run_dir)]
    return {
        "check": check.name,
        "overrides": list(check.overrides),
        "seed": seed,
        "null": null,
        "initial": initial,
        "final": out.get("results", {}),
        "diagnostics": out.get("diagnostics", {}),
        "rows": rows,
    }
