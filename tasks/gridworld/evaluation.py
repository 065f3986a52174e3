"""GridWorld evaluation extras: goal-side shares and the paper's Figure 2 (action field and trajectories)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import torch
from tensordict import TensorDict

from refpo_warp.utils.atomic_files import save_figure

FIGURE_STARTS = ((17, 12), (11, 13), (6, 9), (20, 17))  # (x, y) starts of the paper's trajectory panel
FIGURE_FLOW_STEPS = (10, 1)
# The generic means these numbers stand for (one name per metric in eval.json): success_rate is success_mean, and
# top_share / bottom_share carry reached_top_mean (= top_share x success_rate).
REPLACES = ("success_mean", "reached_top_mean")


def summarize(episodes: dict[str, torch.Tensor]) -> dict[str, float]:
    """Success rate and the share of successes ending at the top (y >= size-2) vs the bottom goal rows."""
    success = episodes["success"]
    n_success = float(success.sum())
    top = float(episodes["reached_top"].sum())
    return {
        "success_rate": float(success.mean()) if success.numel() else 0.0,
        "top_share": top / n_success if n_success else 0.0,
        "bottom_share": (n_success - top) / n_success if n_success else 0.0,
    }


def dataset_summary(dataset) -> dict[str, float]:
    """A demonstration dataset's numbers as ``summarize`` gives a policy's: success rate and the goal bands' shares
    (an episode succeeds where it terminates; its last observation says which band it reached)."""
    success = [bool(e.terminations[-1]) for e in dataset.episodes]
    top = sum(1 for e, ok in zip(dataset.episodes, success) if ok and e.observations[-1, 1] > 0)
    n_success = sum(success)
    return {
        "success_rate": n_success / len(success),
        "top_share": top / n_success if n_success else 0.0,
        "bottom_share": (n_success - top) / n_success if n_success else 0.0,
    }


def _obs(cells: torch.Tensor, size: int) -> TensorDict:
    c = (size - 1) / 2
    return TensorDict({"policy": (cells.float() - c) / c}, batch_size=[cells.shape[0]])


def _sample(actor, obs, flow_steps: int | None) -> torch.Tensor:
    """Stochastic actions; ``flow_steps`` Euler steps for a flow policy, None for a Gaussian one."""
    if flow_steps is None:
        return actor(obs, stochastic_output=True)
    return actor(obs, stochastic_output=True, num_steps=flow_steps)


def _draw_grid(ax, size: int) -> None:
    for rows in ((0, 1), (size - 2, size - 1)):
        ax.axhspan(rows[0] - 0.5, rows[1] + 0.5, color="#b6e3b6", zorder=0)
    ax.set_xlim(-0.5, size - 0.5)
    ax.set_ylim(-0.5, size - 0.5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


@torch.inference_mode()
def action_field(actor, size: int, flow_steps: int | None, samples: int = 8, device: str = "cpu") -> torch.Tensor:
    """Sampled actions at every cell: (size, size, samples, 2), indexed [y, x]."""
    ys, xs = torch.meshgrid(torch.arange(size), torch.arange(size), indexing="ij")
    cells = torch.stack([xs.reshape(-1), ys.reshape(-1)], dim=-1).repeat_interleave(samples, 0).to(device)
    actions = _sample(actor, _obs(cells, size), flow_steps)[:, :2].clamp(-1, 1)  # an action chunk's first move
    return actions.reshape(size, size, samples, 2).cpu()


@torch.inference_mode()
def rollouts(actor, env, flow_steps: int | None, starts=FIGURE_STARTS, episodes_per_start: int = 20) -> list[list]:
    """Trajectories (lists of (x, y)) of ``episodes_per_start`` episodes from each start (env has that many envs)."""
    n = env.num_envs
    if n != len(starts) * episodes_per_start:
        raise ValueError(f"need {len(starts) * episodes_per_start} envs, got {n}")
    start = torch.tensor(starts, dtype=torch.int32).repeat_interleave(episodes_per_start, 0)
    env.reset_to(start)
    paths = [[tuple(p)] for p in start.tolist()]
    alive = torch.ones(n, dtype=torch.bool)
    obs = env.get_observations()
    for _ in range(env.max_episode_length):
        # Positions before the step; an env that finishes this step auto-resets, so read its end cell from
        # the action (the grid moves are deterministic given the clipped, rounded action).
        before = env.positions.cpu().clone()
        actions = _sample(actor, obs, flow_steps)[:, :2]  # an action chunk's first move, closed-loop
        obs, _, dones, _ = env.step(actions)
        move = torch.where(actions.abs() > 0.5, actions.sign(), torch.zeros_like(actions)).cpu().int()
        after = (before + move).clamp(0, env.cfg.size - 1)
        for i in torch.nonzero(alive).flatten().tolist():
            paths[i].append(tuple(after[i].tolist()))
        alive &= ~dones.cpu()
        if not alive.any():
            break
    return paths


def figures(run_dir: Path, actor, cfg: dict) -> list[Path]:
    """Write ``gridworld_field_N{10,1}.png`` and ``gridworld_trajectories_N{10,1}.png`` into the run dir (a Gaussian
    policy: ``gridworld_field.png`` and ``gridworld_trajectories.png``)."""
    from refpo_warp.envs.registry import make_env
    from refpo_warp.tasks.gridworld import TASKS

    size = int(cfg["env"].get("size", 25))
    device = next(actor.parameters()).device
    env_cfg = {**cfg["env"], "action_chunk": 1, "reset_group_size": 1}  # one move per step from the set starts
    env = make_env(  # the family's own task: a config folder's variant of it has the same env
        TASKS[0], num_envs=len(FIGURE_STARTS) * 20, device=str(device), seed=cfg["seed"] + 20_000, **env_cfg
    )
    written = []
    for n in FIGURE_FLOW_STEPS if hasattr(actor, "num_flow_steps") else (None,):
        suffix, policy = (f"_N{n}", f"{n}-step flow") if n else ("", "Gaussian policy")
        field = action_field(actor, size, n, device=str(device))
        fig, ax = plt.subplots(figsize=(5, 5))
        _draw_grid(ax, size)
        ys, xs = torch.meshgrid(torch.arange(size), torch.arange(size), indexing="ij")
        for s in range(field.shape[2]):
            ax.quiver(
                xs,
                ys,
                field[:, :, s, 0],
                field[:, :, s, 1],
                angles="xy",
                scale_units="xy",
                scale=2.2,
                width=0.004,
                alpha=0.35,
                color="#1f4e9c",
            )
        ax.set_title(f"Sampled actions, {policy}")
        path = Path(run_dir) / f"gridworld_field{suffix}.png"
        save_figure(fig, path, dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append(path)

        fig, ax = plt.subplots(figsize=(5, 5))
        _draw_grid(ax, size)
        colors = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd")
        for i, path_cells in enumerate(rollouts(actor, env, n)):
            xy = torch.tensor(path_cells, dtype=torch.float32)
            jitter = (torch.rand(2) - 0.5) * 0.3  # separate overlapping paths
            ax.plot(xy[:, 0] + jitter[0], xy[:, 1] + jitter[1], color=colors[i // 20], alpha=0.45, lw=1)
        for (x, y), c in zip(FIGURE_STARTS, colors):
            ax.plot(x, y, "o", color=c, ms=8, mec="k")
        ax.set_title(f"Rollouts from fixed starts, {policy}")
        path = Path(run_dir) / f"gridworld_trajectories{suffix}.png"
        save_figure(fig, path, dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append(path)
    return written
