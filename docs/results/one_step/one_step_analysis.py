#!/usr/bin/env python
"""What ReFPO's one-step sampler does (the investigation behind this folder's README):

    python docs/results/one_step/one_step_analysis.py SWEEP_DIR [out=DIR] [task=ID] [seed=K] [states=256] [noises=16]
        [every=1] [intervene=ITERATION] [intervene_iterations=5] [device=cpu] [curves_only=false]

Reads a refpo sweep dir whose runs logged the one-step diagnostic and kept checkpoints (configs/sweep/
cpu_reflow_pairs.yaml) and writes into out= (default SWEEP_DIR/one_step):

- <task>_one_step.png for every task: per method (mean over seeds, their range as a band) the periodic N = 10 and
  N = 1 evaluation returns, the one-step error |a_1(eps) - a_N(eps)|^2, the one-step ratio (error / spread) and the
  Reflow coefficient, over env steps;
- for task= (default dmc_point_mass) and seed=: the sampler probe of every checkpoint (every=k: each k-th) of every
  method on the states its own N-step policy visits (one_step_probes.py beside this script: one-step error, spread,
  distance of a_1 to the policy's mean action, a_1's own spread, saturation), <task>_probe_seed<k>.png; the
  velocity error by flow time of the last checkpoints along the sampler's paths and on independent pairs,
  <task>_velocity_by_tau_seed<k>.png; and, for dmc_point_mass, the paths the 1-step and 10-step policies drive from
  the same 8 initial states, <task>_paths_seed<k>.png;
- with intervene=<iteration>: from that checkpoint of the sweep's "refpo" run (independent pairs), a few training
  iterations under each of a few single changes (lambda 0 / 0.2, only positive or only negative advantages, coupled
  pairs), the same first rollout for all; the one-step error on fixed states, the velocity error by tau on the
  sampler's paths and the returns after them, <task>_intervention_seed<k>.png;
- one_step.json with every number behind the figures.

screen=<sweep> (with intervene=<iteration>) screens the sweep's candidates instead (configs/sweep/cpu_onestep.yaml):
from that checkpoint of the "refpo" run of every seed, intervene_iterations iterations under each candidate's
overrides and under ReFPO's own rule, the same first rollout for all, then the one-step error on the checkpoint's
N-step states and the N = 10 and N = 1 returns; <task>_screen.md and screen.json.

curves_only=true redraws the training figures alone (seconds, as more runs of the sweep finish) and updates their
numbers in an existing one_step.json, keeping its probes and intervention.

    python docs/results/one_step/one_step_analysis.py --page [--check]

writes this folder's README.md whole from README.template.md and the committed files (one_step.json, report/runs.csv,
../cpu_dmc/runs.csv, configs/sweep/cpu_reflow_pairs.yaml, configs/task/_dmc.yaml and criteria.yaml), or with --check
compares it with the page on disk; it trains and loads nothing (the helpers it shares with search.md's script are in
run_rows.py).
"""

import json
import statistics
import sys
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from refpo_warp.cli.guard import EXIT_USAGE, run_guarded
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.utils.errors import ConfigError, DataFileError, unknown

OPTIONS: dict[str, Any] = {  # key=value options of the command line, their types checked in main
    "out": None,
    "task": "dmc_point_mass",
    "seed": 1,
    "states": 256,
    "noises": 16,
    "every": 1,
    "device": "cpu",
    "intervene": None,
    "intervene_iterations": 5,
    "curves_only": False,
    "screen": None,
}
PANELS = [
    ("eval/return_N10", "N = 10 return", False),
    ("eval/return_N1", "N = 1 return", False),
    ("Flow/one_step_error", "one-step error", True),
    ("Flow/one_step_ratio", "one-step ratio", True),
    ("Flow/reflow_coef", "Reflow coefficient λ", False),
]
TAUS = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
PROBE_KEYS = ["one_step_error", "policy_spread", "mean_gap", "one_step_spread"]
PATH_ENVS, PATH_STEPS = 8, 300


def method_runs(sweep: Path) -> dict[str, dict[str, dict[int, Path]]]:
    """{task: {method label: {seed: run dir}}} of the finished runs (those with an eval.json)."""
    out: dict[str, dict[str, dict[int, Path]]] = {}
    for eval_file in sorted(sweep.glob("*/*/seed*/eval.json")):
        run = eval_file.parent
        out.setdefault(run.parent.parent.name, {}).setdefault(run.parent.name, {})[int(run.name[4:])] = run
    if not out:
        raise DataFileError(f"{sweep}: no finished runs (<task>/<method>/seed<k>/eval.json); is it a sweep dir?")
    return out


def training_figures(runs, out: Path) -> dict:
    from refpo_warp.evaluation.curves import plt, readable_log_axis, seed_stats, series
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.utils.atomic_files import save_figure

    numbers: dict[str, dict] = {}
    for task, methods in runs.items():
        fig, axes = plt.subplots(1, len(PANELS), figsize=(3.3 * len(PANELS), 2.8))
        numbers[task] = {}
        for (label, seeds), color in zip(sorted(methods.items()), plt.rcParams["axes.prop_cycle"].by_key()["color"]):
            rows = [read_rows(run) for run in seeds.values()]
            numbers[task][label] = {}
            for ax, (key, title, log) in zip(axes, PANELS):
                steps, mean, low, high = seed_stats([series(r, key) for r in rows])
                if not steps:
                    continue
                ax.plot(np.array(steps) / 1e6, mean, color=color, lw=1.4, label=label)
                ax.fill_between(np.array(steps) / 1e6, low, high, color=color, alpha=0.15, lw=0)
                ax.set_title(title, fontsize=9)
                if log:
                    readable_log_axis(ax)
                numbers[task][label][key] = {"env_steps": steps[-1], "mean": mean[-1], "low": low[-1], "high": high[-1]}
        for ax in axes:
            ax.set_xlabel("env steps (M)", fontsize=8)
            ax.tick_params(labelsize=7)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"{task}: one-step sampler over training (mean over seeds, range shaded)", fontsize=10)
        fig.tight_layout()
        save_figure(fig, out / f"{task}_one_step.png")
        plt.close(fig)
    return numbers


class CheckpointPolicy:
    """One run's actor, loaded from each of its checkpoints in turn (the run's saved config, safe loading)."""

    def __init__(self, run_dir: Path, device: str) -> None:
        from refpo_warp.config.saved import load_run
        from refpo_warp.envs.registry import make_env
        from refpo_warp.evaluation.evaluate_policy import EVAL_SEED_OFFSET
        from refpo_warp.runner.build import build_runner
        from refpo_warp.runner.checkpoints import list_checkpoints

        resolved = load_run(run_dir, {"device": device})
        self.cfg = resolved.cfg
        self.env_options = {**self.cfg["env"], **self.cfg["eval"]["env"]}
        self.seed = self.cfg["seed"] + EVAL_SEED_OFFSET
        self.env = make_env(resolved.task, num_envs=32, device=device, seed=self.seed, **self.env_options)
        _, self.runner = build_runner(resolved, None, env=self.env)
        self.checkpoints = list_checkpoints(run_dir)[::-1]  # oldest first
        self.transform = self.env.cfg.action_transform

    def load(self, path: Path):
        self.runner.load(str(path), map_location=self.runner.device)
        return self.runner.alg.get_policy().eval()

    def states(self, actor, count: int, flow_steps: int):
        """Observations the ``flow_steps``-step policy visits from the reset states (the first 250 steps of 32 envs)."""
        return visited_states(actor, self.env, count, flow_steps)


def visited_states(actor, env, count: int, flow_steps: int):
    from refpo_warp.evaluation.episodes import run_episodes

    def policy(obs):
        return actor.sample(obs, flow_steps, "random", False)

    return run_episodes(policy, env, max_steps=250, record_obs=count)["observations"]


def probe_run(run: Path, options: dict) -> dict:
    import torch
    from one_step_probes import sampler_probe, velocity_error_by_tau

    loaded = CheckpointPolicy(run, options["device"])
    if not loaded.checkpoints:
        raise DataFileError(f"{run}: no checkpoints (model_<iteration>.pt) to probe")
    keys = [*PROBE_KEYS, "saturated_n", "saturated_1"]
    out: dict[str, Any] = {"iterations": [], "states_N": {k: [] for k in keys}, "states_1": {k: [] for k in keys}}
    picked = loaded.checkpoints[:: options["every"]]
    picked += [] if picked[-1] == loaded.checkpoints[-1] else loaded.checkpoints[-1:]
    for path in picked:
        actor = loaded.load(path)
        out["iterations"].append(int(path.stem.split("_")[1]))
        for where, steps in (("states_N", actor.num_flow_steps), ("states_1", 1)):
            obs = loaded.states(actor, options["states"], steps)
            gen = torch.Generator().manual_seed(options["seed"])
            probe = sampler_probe(actor, obs, actor.num_flow_steps, loaded.transform, options["noises"], gen)
            for key in keys:
                out[where][key].append(probe[key])
    obs = loaded.states(actor, options["states"], actor.num_flow_steps)
    gen = torch.Generator().manual_seed(options["seed"])
    out["by_tau"] = velocity_error_by_tau(actor, obs, actor.num_flow_steps, TAUS, 8, gen)
    if loaded.cfg["task"] == "dmc_point_mass":
        out["paths"] = point_mass_paths(loaded, actor)
    return out


def point_mass_paths(loaded: CheckpointPolicy, actor) -> dict:
    """Positions, distance to the target (the origin) and |action| of the 1-step and 10-step policies, the same 8
    initial states (one env seed) and the same noise stream."""
    from one_step_probes import drive

    from refpo_warp.envs.registry import make_env

    out = {}
    for n in (1, actor.num_flow_steps):
        env = make_env(
            "dmc_point_mass", num_envs=PATH_ENVS, device=loaded.env.device, seed=loaded.seed, **loaded.env_options
        )
        rolled = drive(actor, env, n, PATH_STEPS, seed=0)
        position = rolled["obs"][..., :2]
        out[f"N={n}"] = {
            "position": position.tolist(),
            "distance": position.norm(dim=-1).tolist(),
            "abs_action": rolled["actions"].clamp(-1, 1).abs().mean(dim=-1).tolist(),
            "return": float(rolled["rewards"].sum(dim=0).mean()),
        }
    return out


# One update rule changed at a time, from the same checkpoint and the same first rollout (the base run: ReFPO with
# independent pairs, the sweep's "refpo"). "advantages" keeps only one sign of the (normalised) advantages.
VARIANTS: dict[str, dict[str, float | str]] = {
    "as trained (λ = 0.04)": {},
    "λ = 0": {"algorithm.reflow_coef": 0.0},
    "λ = 0, A > 0 only": {"algorithm.reflow_coef": 0.0, "advantages": "positive"},
    "λ = 0, A < 0 only": {"algorithm.reflow_coef": 0.0, "advantages": "negative"},
    "λ = 0.2": {"algorithm.reflow_coef": 0.2},
    "coupled, λ = 0.04": {"algorithm.reflow_pairs": "coupled"},
    "coupled, λ = 0.2": {"algorithm.reflow_pairs": "coupled", "algorithm.reflow_coef": 0.2},
}


def one_sign(minibatches, sign: str):
    """``alg.minibatches`` with the advantages of the other sign set to 0 (after their normalisation)."""
    import dataclasses

    def batches():
        for batch in minibatches():
            adv = batch.advantages.clamp(min=0) if sign == "positive" else batch.advantages.clamp(max=0)
            yield dataclasses.replace(batch, advantages=adv)

    return batches


def screen(seeds: dict[str, dict[int, Path]], task: str, options: dict, out: Path) -> Path:
    """The ``screen=`` mode (module docstring): every seed of the "refpo" runs, ReFPO's own rule and every candidate
    of the sweep; writes ``<task>_screen.md`` and ``screen.json``, returns the Markdown file."""
    from refpo_warp.studies.grid.spec import load_sweep

    runs = seeds.get("refpo")
    if not runs:
        raise ConfigError(f"screen= needs the sweep's 'refpo' runs of {task} (checkpoints every few iterations)")
    sweep = load_sweep(str(options["screen"]))
    candidates: dict[str, dict] = {"ReFPO (the paper's rule)": {}}
    candidates.update({m.name: dict(m.overrides) for m in sweep.methods})
    iteration, iterations = int(options["intervene"]), int(options["intervene_iterations"])
    results = {
        seed: intervene(run, iteration, iterations, {**options, "seed": seed}, candidates, light=True)
        for seed, run in sorted(runs.items())
    }
    write_numbers({"iteration": iteration, "iterations": iterations, "seeds": results}, out / "screen.json")
    lines = [
        f"# Screen on {task}: {iterations} iterations from the iteration-{iteration} checkpoint of ReFPO",
        "",
        (
            "One-step error (on the checkpoint's N-step states) and N = 10 / N = 1 returns (32 episodes) per seed "
            f"{', '.join(map(str, sorted(runs)))}; the checkpoint itself first."
        ),
        "",
        "| candidate | " + " | ".join(f"seed {s}: error, N=10 / N=1" for s in sorted(runs)) + " |",
        "|---|" + "---|" * len(runs),
    ]

    def cells(get) -> str:
        return " | ".join(
            f"{r['states_N']['one_step_error']:.3f}, {r['returns']['N=10']:.0f} / {r['returns']['N=1']:.0f}"
            for r in (get(results[s]) for s in sorted(runs))
        )

    lines.append(f"| checkpoint (iteration {iteration}) | " + cells(lambda r: r["checkpoint"]) + " |")
    for name in candidates:
        lines.append(f"| {name} | " + cells(lambda r, name=name: r["variants"][name]) + " |")
    path = out / f"{task}_screen.md"
    from refpo_warp.utils.atomic_files import write_text

    write_text(path, "\n".join(lines) + "\n")
    return path


def evaluate_returns(actor, cfg: dict, device: str) -> dict[str, float]:
    """N = 10 and N = 1 returns of 32 evaluation episodes (the run's evaluation protocol and env seed)."""
    from refpo_warp.envs.registry import make_env
    from refpo_warp.evaluation.episodes import run_episodes
    from refpo_warp.evaluation.evaluate_policy import EVAL_SEED_OFFSET, make_policy

    out = {}
    for n in (actor.num_flow_steps, 1):
        env = make_env(
            cfg["task"],
            num_envs=32,
            device=device,
            seed=cfg["seed"] + EVAL_SEED_OFFSET,
            **{**cfg["env"], **cfg["eval"]["env"]},
        )
        policy = make_policy(actor, n, cfg["eval"]["initial_noise"][0], cfg["eval"]["perturbation"])
        out[f"N={n}"] = float(run_episodes(policy, env)["return"].mean())
    return out


def intervene(
    run: Path, iteration: int, iterations: int, options: dict, variants: dict = VARIANTS, light: bool = False
) -> dict:
    """From checkpoint ``iteration`` of ``run``: ``iterations`` training iterations under each of ``variants``, then
    the sampler probe on fixed states (those the checkpoint's N-step and 1-step policies visit), the velocity error
    by tau on its own paths (not if ``light``), and the evaluation returns."""
    import contextlib
    import io

    import torch
    from one_step_probes import sampler_probe, velocity_error_by_tau

    from refpo_warp.config.saved import load_run
    from refpo_warp.runner.build import build_runner, seed_everything

    checkpoint = run / f"model_{iteration}.pt"
    if not checkpoint.is_file():
        raise DataFileError(f"{checkpoint} not found: intervene= must name a checkpoint iteration of {run}")
    device = options["device"]
    base = CheckpointPolicy(run, device)
    actor = base.load(checkpoint)
    fixed = {"states_N": base.states(actor, options["states"], actor.num_flow_steps)}
    if not light:
        fixed["states_1"] = base.states(actor, options["states"], 1)

    def measure(actor) -> dict:
        out: dict[str, Any] = {}
        for where, obs in fixed.items():
            gen = torch.Generator().manual_seed(options["seed"])
            out[where] = sampler_probe(actor, obs, actor.num_flow_steps, base.transform, options["noises"], gen)
        if not light:
            gen = torch.Generator().manual_seed(options["seed"])
            out["own_path_by_tau"] = velocity_error_by_tau(
                actor, fixed["states_N"], actor.num_flow_steps, TAUS, 8, gen
            )["own_path"]
        out["returns"] = evaluate_returns(actor, base.cfg, device)
        return out

    results: dict[str, Any] = {"checkpoint": measure(actor), "iterations": iterations, "variants": {}}
    for name, change in variants.items():
        print(f"[one_step] {run.name} from iteration {iteration}: {iterations} iterations, {name}", flush=True)
        overrides = {"device": device, **{k: v for k, v in change.items() if k != "advantages"}}
        resolved = load_run(run, overrides)
        cfg = resolved.cfg
        with contextlib.redirect_stdout(io.StringIO()):
            _, runner = build_runner(resolved, None)
            runner.load(str(checkpoint), map_location=runner.device)
            if "advantages" in change:
                runner.alg.minibatches = one_sign(runner.alg.minibatches, change["advantages"])
            seed_everything(cfg["seed"])
            runner.learn_chunk(iterations, runner.current_learning_iteration + 1 + iterations)
        results["variants"][name] = measure(runner.alg.get_policy().eval())
    return results


def intervention_figure(task: str, seed: int, iteration: int, results: dict, out: Path) -> Path:
    from refpo_warp.evaluation.curves import plt, readable_log_axis
    from refpo_warp.utils.atomic_files import save_figure

    names = list(results["variants"])
    start = results["checkpoint"]
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 3.4))
    x = np.arange(len(names))
    for offset, where in ((-0.2, "states_N"), (0.2, "states_1")):
        values = [results["variants"][n][where]["one_step_error"] for n in names]
        axes[0].bar(x + offset, values, width=0.4, label=f"on the {where[7:]}-step policy's states")
        axes[0].axhline(start[where]["one_step_error"], color="C0" if where == "states_N" else "C1", ls=":", lw=1)
    axes[0].set_xticks(x, names, rotation=35, ha="right", fontsize=7)
    axes[0].set_title(f"one-step error after {results['iterations']} iterations (dotted: before)", fontsize=9)
    axes[0].legend(fontsize=7)
    for name in names:
        axes[1].plot(TAUS, results["variants"][name]["own_path_by_tau"], "o-", ms=3, label=name)
    axes[1].plot(TAUS, start["own_path_by_tau"], "k:", label="checkpoint")
    readable_log_axis(axes[1])
    axes[1].set_xlabel("flow time τ", fontsize=8)
    axes[1].set_title("velocity error on the sampler's own paths", fontsize=9)
    axes[1].legend(fontsize=6)
    for offset, key in ((-0.2, "N=10"), (0.2, "N=1")):
        axes[2].bar(x + offset, [results["variants"][n]["returns"][key] for n in names], width=0.4, label=key)
    axes[2].set_xticks(x, names, rotation=35, ha="right", fontsize=7)
    axes[2].set_title("evaluation return after them", fontsize=9)
    axes[2].legend(fontsize=7)
    fig.suptitle(f"{task}, seed {seed}: one rule changed at a time from checkpoint {iteration}", fontsize=10)
    fig.tight_layout()
    path = save_figure(fig, out / f"{task}_intervention_seed{seed}.png")
    plt.close(fig)
    return path


def probe_figures(task: str, seed: int, probes: dict[str, dict], out: Path) -> list[Path]:
    from refpo_warp.evaluation.curves import plt, readable_log_axis
    from refpo_warp.utils.atomic_files import save_figure

    colors = dict(zip(sorted(probes), plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    titles = {
        "one_step_error": "|a_1(ε) − a_N(ε)|²",
        "policy_spread": "spread of a_N over ε",
        "mean_gap": "|a_1(ε) − mean_ε a_N|²",
        "one_step_spread": "spread of a_1 over ε",
    }
    paths = []
    fig, axes = plt.subplots(1, len(PROBE_KEYS), figsize=(3.4 * len(PROBE_KEYS), 2.8))
    for label, probe in sorted(probes.items()):
        for ax, key in zip(axes, PROBE_KEYS):
            for where, style in (("states_N", "-"), ("states_1", "--")):
                ax.plot(
                    probe["iterations"],
                    np.maximum(probe[where][key], 1e-6),
                    style,
                    color=colors[label],
                    lw=1.3,
                    label=label if where == "states_N" else None,
                )
    for ax, key in zip(axes, PROBE_KEYS):
        readable_log_axis(ax)
        ax.set_title(titles[key], fontsize=9)
        ax.set_xlabel("iteration", fontsize=8)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        f"{task}, seed {seed}: the sampler at every checkpoint, on the states its N-step policy (solid) and "
        "its 1-step policy (dashed) visit",
        fontsize=10,
    )
    fig.tight_layout()
    paths.append(save_figure(fig, out / f"{task}_probe_seed{seed}.png"))
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(7.5, 2.9), sharey=True)
    for label, probe in sorted(probes.items()):
        for ax, key in zip(axes, ("own_path", "independent")):
            ax.plot(probe["by_tau"]["tau"], probe["by_tau"][key], "o-", ms=3, color=colors[label], label=label)
    axes[0].set_title("own path: x_τ on (ε₀, a_N(ε₀)), target a_N − ε₀", fontsize=8)
    axes[1].set_title("independent pairs: fresh ε, target a_N − ε", fontsize=8)
    for ax in axes:
        readable_log_axis(ax)
        ax.set_xlabel("flow time τ", fontsize=8)
    axes[0].set_ylabel("|v(x_τ, τ) − target|²", fontsize=8)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{task}, seed {seed}: velocity error by τ at the last checkpoint", fontsize=10)
    fig.tight_layout()
    paths.append(save_figure(fig, out / f"{task}_velocity_by_tau_seed{seed}.png"))
    plt.close(fig)

    with_paths = {k: v["paths"] for k, v in sorted(probes.items()) if "paths" in v}
    if with_paths:
        fig, axes = plt.subplots(2, len(with_paths), figsize=(3.2 * len(with_paths), 6.0), squeeze=False)
        for col, (label, rolled) in enumerate(with_paths.items()):
            for key, style in zip(rolled, ("--", "-")):
                position = np.array(rolled[key]["position"])
                for env in range(position.shape[1]):
                    axes[0, col].plot(position[:, env, 0], position[:, env, 1], style, lw=0.9, color=f"C{env}")
                distance = np.array(rolled[key]["distance"]).mean(axis=1)
                axes[1, col].plot(distance, style, color="k", label=f"{key}: return {rolled[key]['return']:.0f}")
            axes[0, col].add_patch(plt.Circle((0, 0), 0.015, color="r", alpha=0.6))
            axes[0, col].set_aspect("equal")
            axes[0, col].set_title(f"{label} (dashed N = 1, solid N = 10)", fontsize=8)
            axes[1, col].set_xlabel(f"step (first {PATH_STEPS})", fontsize=8)
            axes[1, col].set_ylabel("mean distance to target", fontsize=8)
            axes[1, col].legend(fontsize=7)
        fig.suptitle(f"{task}, seed {seed}: paths of the 1-step and 10-step policies from 8 shared starts", fontsize=10)
        fig.tight_layout()
        paths.append(save_figure(fig, out / f"{task}_paths_seed{seed}.png"))
        plt.close(fig)
    return paths


def rounded(value, digits: int = 4):
    """``value`` with every float rounded to ``digits`` significant digits (the JSON behind the figures, kept small)."""
    if isinstance(value, float):
        return float(f"{value:.{digits}g}")
    if isinstance(value, dict):
        return {key: rounded(item, digits) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [rounded(item, digits) for item in value]
    return value


def write_numbers(numbers: dict, path: Path) -> None:
    """The numbers behind the figures, rounded and compact (the point_mass paths are most of them)."""
    from refpo_warp.utils.atomic_files import write_text

    write_text(path, json.dumps(rounded(numbers), separators=(",", ":")))


# ------------------------------------------------------------------------------------------------ the page (README.md)
HERE = Path(__file__).resolve().parent
PAGE_METHODS = ("fpo", "refpo", "refpo_coupled", "refpo_adaptive")  # the sweep's labels, in the table's order
REFPO_VARIANTS = ("refpo", "refpo_coupled", "refpo_adaptive")
SHORT = {
    "fpo": "FPO",
    "refpo": "independent pairs",
    "refpo_coupled": "coupled pairs",
    "refpo_adaptive": "the adaptive λ",
}


def _g(x: float) -> str:
    """A diagnostic for the prose: three decimals, or two significant digits below 0.001."""
    if x == 0:
        return "0"
    return f"{x:.2g}" if abs(x) < 0.001 else f"{x:.3f}" if abs(x) < 1 else f"{x:.2f}"


def _roles(variants: dict) -> dict[str, str]:
    """The intervention's variants by what they change (VARIANTS' overrides), so the page names each by role."""
    roles = {}
    for name, change in VARIANTS.items():
        if name not in variants:
            raise DataFileError(f"one_step.json's intervention has no variant '{name}' (VARIANTS of this script)")
        coupled = change.get("algorithm.reflow_pairs") == "coupled"
        coef = change.get("algorithm.reflow_coef")
        if not change:
            roles["base"] = name
        elif change.get("advantages") == "positive":
            roles["positive"] = name
        elif change.get("advantages") == "negative":
            roles["negative"] = name
        elif coef == 0.0 and not coupled:
            roles["no_reflow"] = name
        elif coupled and coef is None:
            roles["coupled"] = name
        elif coupled:
            roles["coupled_high"] = name
        else:
            roles["high"] = name
    return roles


def page_values() -> dict:
    import run_rows as st

    from refpo_warp.studies.reports.committed_runs import seeds_text

    rules = st.criteria()
    below = rules["collapse_below"]
    settle_window = rules["summaries"]["settle_window"]
    alike_within = rules["summaries"]["alike_within"]
    small_tau_below = rules["summaries"]["small_tau"]
    numbers = json.loads((HERE / "one_step.json").read_text(encoding="utf-8"))
    training, probes, inter = numbers["training"], numbers["probes"], numbers["intervention"]
    rows, dmc = st.read_rows(HERE / "report" / "runs.csv"), st.read_rows(st.CPU_DMC_RUNS)
    spec = st.sweep_spec(st.ROOT / "configs" / "sweep" / "cpu_reflow_pairs.yaml")
    names = st.method_names(spec)
    tasks = list(spec["tasks"])
    pm_task = "dmc_point_mass"
    MULTI, ONE = st.MULTI, st.ONE

    def runs(label, task, key, source=rows):
        return st.per_seed(source, label, task, key)

    def lam(label, task="dmc_point_mass"):
        return training[task][label]["Flow/reflow_coef"]

    seed = int(next(HERE.glob("dmc_point_mass_probe_seed*.png")).stem.rsplit("seed", 1)[1])
    out: dict = {"seed": seed, "collapse": f"{below:g}"}

    # ------------------------------------------------------------------------------------- cpu_dmc's standing
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
        f"in its ReFPO runs (seeds {seeds_text(dmc_seeds)}) the 1-step return collapses in " + st.words(parts)
    )

    # ------------------------------------------------------------------------------------- in short
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
        f"{_g(err_n[0])} at iteration {its[0]}, {_g(err_n[len(its) // 2])} at {its[len(its) // 2]}, "
        f"{_g(err_n[-1])} at {its[-1]}, while the spread of a_N falls from {spread_n[0]:.2f} to {spread_n[-1]:.2f}), "
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
    role = _roles(variants)

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
            else f"with 10-step returns apart from ReFPO's for {st.words([names[lb] for lb in apart])}"
        )
        + f" ({iv('refpo_coupled')} and {iv('refpo_adaptive')} against {iv('refpo')}). "
        + (
            "Neither is an answer yet."
            if any(len(held[lb]) < len(pm_one[lb]) for lb in others)
            else "Both hold the 1-step return in every seed."
        )
    )

    # ------------------------------------------------------------------------------------- how it was measured
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

    # ------------------------------------------------------------------------------------- the table
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

    # ------------------------------------------------------------------------------------- directions
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
            f"{st.short(t)} {' and '.join(_g(statistics.fmean(one_step_eval[(lb, t)].values())) for lb in others)} "
            f"against {_g(statistics.fmean(one_step_eval[('refpo', t)].values()))}"
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
            f"{st.words([str(s) for s in re_below[lb]]) if re_below[lb] else 'none'}"
            + (
                f" and above it in seed{'s' if len(re_above[lb]) != 1 else ''} "
                f"{st.words([str(s) for s in re_above[lb]])}"
                if re_above[lb]
                else ""
            )
            for lb in others
        )
        + "."
    )
    out["directions"] = "\n".join(bullets)

    # ------------------------------------------------------------------------------------- over training
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
                f"{rng(t['Flow/one_step_error'], _g)} | {rng(t['Flow/one_step_ratio'], ratio_fmt)} | "
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
        f"On point_mass, FPO's one-step error (λ = 0) ends at {_g(fpo_err['mean'])} and ReFPO's at "
        f"{_g(ref_err['mean'])} (λ = {lam('refpo')['mean']:g}): "
        + (
            "the independent term leaves it about where FPO has it (the ranges overlap). "
            if fpo_err["high"] >= ref_err["low"] and ref_err["high"] >= fpo_err["low"]
            else "the ranges are apart. "
        )
    )
    text += (
        "The adaptive λ ends at "
        + st.words([f"{value:g} in every seed on {st.words(ts)}" for value, ts in fixed.items()])
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

    # ------------------------------------------------------------------------------------- paths
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
        f"action error suggests; on {st.words([st.short(t) for t in rest])}, ReFPO's one-step error (eval) of "
        f"{' and '.join(_g(cost[t][0]) for t in rest)}, against point_mass's {_g(cost[pm_task][0])}, goes with 1-step "
        f"returns of {' and '.join(f'{cost[t][1]:.0f}' for t in rest)} against 10-step ones of "
        f"{' and '.join(f'{cost[t][2]:.0f}' for t in rest)}."
    )

    # ------------------------------------------------------------------------------------- probes
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
            f"({_g(f_err[small[-1]])} against {_g(r_err[small[-1]])}) and rises late ({_g(f_err[-1])} at {its[-1]}), "
            if through is not None
            else f"its one-step error ends at {_g(f_err[-1])}, "
        )
        + f"its policy narrows less (spread {f_spread[0]:.2f} → {f_spread[-1]:.2f}, against "
        f"{spread_n[0]:.2f} → {spread_n[-1]:.2f} for ReFPO), and its field is far from straight on its own paths "
        f"(velocity error {st.span(f_own, 1)} by τ). In seed {seed} its final returns are {fm[seed]:.0f} at N = 10 and "
        f"{fo[seed]:.1f} at N = 1, and its paths end {fd10:.3f} (N = 10) and {fd1:.3f} (N = 1) from the target on "
        f"average, against {np.array(paths[f'N={len(TAUS)}']['distance'])[-1].mean():.3f} for ReFPO's 10-step policy."
    )

    # ------------------------------------------------------------------------------------- by tau
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
        f"{_g(err_n[first])} at iteration {its[first]} to {_g(err_n[-1])} at {its[-1]}. With coupled pairs the "
        f"own-path error at τ = 0, the one a single Euler step reads, is {coupled_own[0]:.2f} against "
        "independent pairs' "
        f"{own[0]:.2f}."
    )

    # ------------------------------------------------------------------------------------- intervention
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

    # ------------------------------------------------------------------------------------- mechanism
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

    # ------------------------------------------------------------------------------------- other tasks
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
        f"{' and '.join(_g(cp_err[lb]) for lb in others)} and lift the 10-step return of ReFPO's weakest seed (seed "
        f"{weakest}: {cp_multi[weakest]:.1f}; "
        + ", ".join(f"{SHORT[lb]} {runs(lb, cp, MULTI).get(weakest, float('nan')):.1f}" for lb in others)
        + f"). On reacher_easy the one-step error falls as well ({' and '.join(_g(re_err[lb]) for lb in others)} "
        f"against {_g(re_err['refpo'])}) and the 10-step return falls below ReFPO's in "
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

    # ------------------------------------------------------------------------------------- diagnostics, leads
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


def write_readme(argv: list[str]) -> int:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args("README.md of docs/results/one_step from its template and the committed data files")
    parser.add_argument("--page", action="store_true", help="write the page (the default when --check is not given)")
    args = parser.parse_args(argv)
    same = write_page(HERE / "README.template.md", page_values(), check=args.check)
    if args.check:
        return 0 if same else 1
    print(f"{HERE / 'README.md'}: {'unchanged' if same else 'written'}")
    return 0


def main(argv: list[str]) -> int:
    if argv and argv[0] in ("--page", "--check"):
        return write_readme(argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else EXIT_USAGE

    def analyse() -> None:
        sweep = Path(argv[0])
        if not sweep.is_dir():
            raise ConfigError(f"{sweep}: no such sweep directory (a refpo sweep output dir)")
        options: dict[str, Any] = dict(OPTIONS)
        for key, value in parse_overrides(argv[1:]).items():
            if key not in OPTIONS:
                raise unknown("option", key, list(OPTIONS))
            options[key] = value
        for key in ("seed", "states", "noises", "every", "intervene_iterations"):
            if not isinstance(options[key], int) or options[key] < (0 if key == "seed" else 1):
                raise ConfigError(f"{key}={options[key]!r} is invalid; expected a positive integer")
        if not isinstance(options["curves_only"], bool):
            raise ConfigError(f"curves_only={options['curves_only']!r} is invalid; expected true or false")
        out = Path(options["out"] or sweep / "one_step")
        out.mkdir(parents=True, exist_ok=True)
        runs = method_runs(sweep)
        if options["task"] not in runs:
            raise unknown("task", options["task"], list(runs))
        numbers = {"training": {} if options["screen"] else training_figures(runs, out), "probes": {}}
        if options["curves_only"]:
            previous = out / "one_step.json"
            kept = json.loads(previous.read_text()) if previous.is_file() else {}
            write_numbers({**kept, "training": numbers["training"]}, previous)
            print(previous)
            return
        task, seed = options["task"], options["seed"]
        if options["screen"] is not None:
            if options["intervene"] is None:
                raise ConfigError("screen= needs intervene=<checkpoint iteration> (the iteration to screen from)")
            print(screen(runs[task], task, options, out))
            return
        for label, seeds in sorted(runs[task].items()):
            if seed in seeds:
                print(f"[one_step] probing {task}/{label}/seed{seed}", flush=True)
                numbers["probes"][label] = probe_run(seeds[seed], options)
        for path in probe_figures(task, seed, numbers["probes"], out):
            print(path)
        if options["intervene"] is not None:
            base = runs[task].get("refpo", {}).get(seed)
            if base is None:
                raise ConfigError(f"intervene= needs the sweep's 'refpo' run of {task} seed {seed}")
            results = intervene(base, int(options["intervene"]), int(options["intervene_iterations"]), options)
            numbers["intervention"] = {"iteration": int(options["intervene"]), **results}
            print(intervention_figure(task, seed, int(options["intervene"]), results, out))
        write_numbers(numbers, out / "one_step.json")
        print(out / "one_step.json")

    return run_guarded(analyse)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
