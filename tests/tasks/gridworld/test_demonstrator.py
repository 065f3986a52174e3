"""GridWorld's scripted demonstrator: straight to the nearer goal band outside the middle band, two modes inside it."""

import torch
from tensordict import TensorDict

from refpo_warp.tasks.gridworld.demonstrator import Demonstrator


def obs_at(rows, size=25):
    c = (size - 1) / 2
    cells = torch.tensor([[5, y] for y in rows], dtype=torch.float32)
    return TensorDict({"policy": (cells - c) / c}, batch_size=[len(rows)])


def test_outside_the_band_it_walks_to_the_nearer_goal():
    demo = Demonstrator(25, torch.Generator().manual_seed(0), up_share=0.7, band=3)
    actions = demo(obs_at([2, 5, 8, 16, 19, 22]))
    assert actions[:, 1].tolist() == [-1, -1, -1, 1, 1, 1]
    assert bool((actions[:, 0].abs() <= 1).all())


def test_inside_the_band_it_steps_up_with_up_share():
    demo = Demonstrator(25, torch.Generator().manual_seed(0), up_share=0.7, band=3)
    actions = demo(obs_at([9, 12, 15] * 4000))
    up = float((actions[:, 1] > 0).float().mean())
    assert 0.68 < up < 0.72 and set(actions[:, 1].tolist()) == {-1.0, 1.0}
    # the mean of the two modes, 0.4, rounds to no move: what a Gaussian fitted to them would do
    assert abs(float(actions[:, 1].mean())) <= 0.5
