"""A few training iterations from one checkpoint under single changes of the update rule (VARIANTS), or under a
sweep's candidates (screen=), the same first rollout for all; the one-step error, the velocity error by flow time
and the returns after them, and the intervention figure."""

from pathlib import Path
from typing import Any

import numpy as np
from checkpoint_probes import TAUS, CheckpointPolicy
from numbers_file import write_numbers

from refpo_warp.utils.errors import ConfigError, DataFileError

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
    from refpo_warp.evaluation.evaluate_policy import EVAL_SEED_OFFSET, eval_env_options, make_policy

    out = {}
    for n in (actor.num_flow_steps, 1):
        env = make_env(
            cfg["task"],
            num_envs=32,
            device=device,
            seed=cfg["seed"] + EVAL_SEED_OFFSET,
            **eval_env_options(cfg),
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
