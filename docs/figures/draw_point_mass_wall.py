#!/usr/bin/env python
"""dmc_point_mass_wall's arena as a picture: python docs/figures/draw_point_mass_wall.py
[out=docs/figures/point_mass_wall.png]

The env (default options, Warp cpu) steps its scripted demonstrator (tasks/dmc/demonstrator.py, left_share 0.5) from
fresh resets; the mass's positions are drawn per episode, coloured by the way it went around the wall, next to the
mean of the two ways' actions rolled out from the same starts (it ends against the wall). Behind them, the reward
at rest (zero action) on a grid of positions, from the env's own reward kernel, with contours (of equal path length
to the target around the wall, away from the target).
"""

import sys


def main(argv: list[str]) -> int:
    if any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0
    out = next((a.split("=", 1)[1] for a in argv if a.startswith("out=")), "docs/figures/point_mass_wall.png")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    import torch

    from refpo_warp.envs.registry import make_env, make_env_cfg
    from refpo_warp.tasks.dmc.demonstrator import make_demonstrator
    from refpo_warp.tasks.dmc.point_mass_wall_cfg import ARENA, MASS_RADIUS, TARGET_RADIUS, TARGET_X
    from refpo_warp.utils.atomic_files import save_figure

    task, n, steps = "dmc_point_mass_wall", 16, 400
    cfg = make_env_cfg(task)
    env = make_env(task, num_envs=n, device="cpu", seed=5)
    demo = make_demonstrator(cfg, torch.Generator().manual_seed(1), left_share=0.5)

    def positions(policy) -> np.ndarray:
        obs, seen = env.reset(), []
        for _ in range(steps):
            seen.append(obs["policy"][:, :2].numpy().copy())
            obs, _, _, _ = env.step(policy(obs))
        return np.stack(seen + [obs["policy"][:, :2].numpy()], axis=1)  # (envs, steps + 1, 2)

    paths = positions(demo)
    sides = demo.side.numpy()
    mean_paths = positions(lambda obs: demo.mean_of_ways(obs["policy"]))

    grid = np.linspace(-ARENA, ARENA, 117)
    points = np.stack(np.meshgrid(grid, grid), axis=-1).reshape(-1, 2)
    rewards = []
    for k in range(0, len(points), n):
        chunk = torch.tensor(points[k : k + n], dtype=torch.float32)
        chunk = torch.cat([chunk, chunk[-1:].expand(n - len(chunk), 2)]) if len(chunk) < n else chunk
        env.set_state(chunk, torch.zeros(n, 2))
        rewards.append(env.compute_rewards(torch.zeros(n, 2)).numpy()[: min(n, len(points) - k)])
    reward = np.concatenate(rewards).reshape(len(grid), len(grid))
    a, b = cfg.wall_box()
    reward[(np.abs(points[:, 0]) < a).reshape(reward.shape) & (np.abs(points[:, 1]) < b).reshape(reward.shape)] = np.nan

    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    shade = ax.imshow(reward, origin="lower", extent=(-ARENA, ARENA, -ARENA, ARENA), cmap="Greys", alpha=0.5)
    fig.colorbar(shade, ax=ax, fraction=0.046, pad=0.04, label="reward at rest (max 1 on the target)")
    lines = ax.contour(grid, grid, reward, levels=np.arange(0.225, 0.5, 0.025), colors="#777", linewidths=0.5)
    ax.clabel(lines, lines.levels[::2], fontsize=6, fmt="%.3g")
    t, half = cfg.wall_half_thickness, cfg.wall_half_length
    ax.add_patch(plt.Rectangle((-t, -half), 2 * t, 2 * half, color="#5a4632", zorder=3, label="wall"))
    ax.add_patch(plt.Rectangle((-a, -b), 2 * a, 2 * b, fill=False, ls=":", ec="#5a4632", zorder=3))
    ax.add_patch(plt.Rectangle((-ARENA, -ARENA), 2 * ARENA, 2 * ARENA, fill=False, ec="k", lw=1.2))
    ax.add_patch(plt.Circle((TARGET_X, 0), TARGET_RADIUS, color="#2a9d3a", zorder=4, label="target"))
    s = cfg.start_spread
    ax.add_patch(plt.Rectangle((-0.2 - s, -s), 2 * s, 2 * s, fill=False, ec="#444", zorder=4, label="starts"))
    for path, side in zip(paths, sides):
        ax.plot(*path.T, color="#1f6fd1" if side > 0 else "#e07b1a", lw=1.2, zorder=5)
    for path in mean_paths:
        ax.plot(*path.T, color="#c8102e", lw=1.2, zorder=6)
        ax.add_patch(plt.Circle(path[-1], MASS_RADIUS, color="#c8102e", zorder=6))
    ax.plot([], [], color="#1f6fd1", label=f"demonstrator, left ({int((sides > 0).sum())})")
    ax.plot([], [], color="#e07b1a", label=f"demonstrator, right ({int((sides < 0).sum())})")
    ax.plot([], [], color="#c8102e", label=f"mean of the two ways ({len(mean_paths)})")
    ax.set_xlim(-0.3, 0.3)
    ax.set_ylim(-0.3, 0.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="lower left", fontsize=7.5, framealpha=0.9)
    ax.set_title(
        f"dmc_point_mass_wall: {steps} steps ({steps * env.step_dt:g} s) from {n} resets each; dotted: the region\n"
        "the mass's centre cannot enter",
        fontsize=9,
    )
    save_figure(fig, out, dpi=120, bbox_inches="tight")
    plt.close(fig)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
