"""A scripted GridWorld demonstrator with two modes, for demonstration datasets (``refpo collect task=gridworld``).

Outside a band of rows around the middle it walks straight to the nearer goal band. Inside the band (rows
``mid - band .. mid + band``; the middle row is 12 on the 25-cell grid) both goal bands are about as far, and it
steps up with probability ``up_share`` and down otherwise, drawn afresh at every step: the action distribution there
has two modes (y action +1 or -1), whose mean (2 up_share - 1 = 0.4 at 0.7) rounds to no move. The x action is
uniform in [-1, 1] (|a| > 0.5 moves sideways), so the data covers the grid's columns. The demonstrator is a Markov
policy of the observation alone, so a policy that matches its action distribution in every cell reaches each goal
band in the data's shares.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from tensordict import TensorDict

from refpo_warp.utils.option_rules import Int, Real
from refpo_warp.utils.options import option


@dataclass(frozen=True)
class Options:
    """The demonstrator's options: demonstrator.<option>=value on refpo collect's line."""

    up_share: float = option(0.7, Real(0, 1), "probability of stepping up inside the band")
    band: int = option(3, Int(0, 1000), "rows on each side of the middle row where it steps up or down at random")


class Demonstrator:
    """obs -> actions (num_envs, 2) for the GridWorld of ``size`` cells, drawn with ``generator``."""

    def __init__(self, size: int, generator: torch.Generator, up_share: float = 0.7, band: int = 3) -> None:
        self.size, self.generator, self.up_share, self.band = size, generator, float(up_share), int(band)

    def __call__(self, obs: TensorDict) -> torch.Tensor:
        c = (self.size - 1) / 2
        y = torch.round(obs["policy"][:, 1] * c + c)
        n = y.shape[0]
        up = torch.rand(n, generator=self.generator) < self.up_share
        direction = torch.where(y > c, 1.0, -1.0)  # the nearer goal band
        in_band = (y - c).abs() <= self.band
        direction = torch.where(in_band, torch.where(up, 1.0, -1.0), direction)
        sideways = 2.0 * torch.rand(n, generator=self.generator) - 1.0
        return torch.stack([sideways, direction], dim=-1).to(obs["policy"].device)

    def describe(self) -> dict:
        return {
            "kind": "scripted",
            "task_family": "gridworld",
            "up_share": self.up_share,
            "band": self.band,
            "rule": "nearer goal band outside the middle band; inside it up with probability up_share, else "
            "down, at every step; x action uniform in [-1, 1]",
        }


def make_demonstrator(env_cfg, generator: torch.Generator, **options) -> Demonstrator:
    return Demonstrator(env_cfg.size, generator, **options)
