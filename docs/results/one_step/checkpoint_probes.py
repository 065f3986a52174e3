"""The sampler probe of a run's checkpoints (one_step_probes.py) on the states its own N-step and 1-step policies
visit, the velocity error by flow time of its last checkpoint, point_mass's paths from shared starts, and the
probe figures."""

from pathlib import Path
from typing import Any

import numpy as np

from refpo_warp.utils.errors import DataFileError

TAUS = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
PROBE_KEYS = ["one_step_error", "policy_spread", "mean_gap", "one_step_spread"]
PATH_ENVS, PATH_STEPS = 8, 300


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
