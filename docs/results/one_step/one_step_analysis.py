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
"""

import json
import sys
from pathlib import Path

import numpy as np
import torch

from refpo_warp.cli.guard import EXIT_USAGE, run_guarded
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.utils.errors import ConfigError, DataFileError, unknown

OPTIONS = {
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

    numbers = {}
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
    from one_step_probes import sampler_probe, velocity_error_by_tau

    loaded = CheckpointPolicy(run, options["device"])
    if not loaded.checkpoints:
        raise DataFileError(f"{run}: no checkpoints (model_<iteration>.pt) to probe")
    keys = [*PROBE_KEYS, "saturated_n", "saturated_1"]
    out = {"iterations": [], "states_N": {k: [] for k in keys}, "states_1": {k: [] for k in keys}}
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
VARIANTS = {
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
    from refpo_warp.sweeps.spec import load_sweep

    runs = seeds.get("refpo")
    if not runs:
        raise ConfigError(f"screen= needs the sweep's 'refpo' runs of {task} (checkpoints every few iterations)")
    sweep = load_sweep(str(options["screen"]))
    candidates = {"ReFPO (the paper's rule)": {}}
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
        out = {}
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

    results = {"checkpoint": measure(actor), "iterations": iterations, "variants": {}}
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


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else EXIT_USAGE

    def analyse() -> None:
        sweep = Path(argv[0])
        if not sweep.is_dir():
            raise ConfigError(f"{sweep}: no such sweep directory (a refpo sweep output dir)")
        options = dict(OPTIONS)
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
