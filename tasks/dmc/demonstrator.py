"""The DMC family's scripted demonstrator, for dmc_point_mass_wall (``refpo collect task=dmc_point_mass_wall
demonstrator=scripted``): a PD controller on waypoints around the left (+y) or right (-y) end of the wall, then onto
the target, the way drawn per episode with probability ``left_share`` for left.

Geometry (``point_mass_wall_cfg``): the mass's centre cannot enter the box (-a, a) x (-b, b), the wall grown by the
mass's radius (a = wall_half_thickness + 0.01, b = wall_half_length + 0.01). Way s (+1 left, -1 right) aims at
W1 = (0, s Y) (the middle of the gap beyond the wall's end, Y = b + c with clearance c = min(0.05, (0.29 - b) / 2))
until the mass is beyond that end (s y > b + c / 2), then at W2 = (a + c, s Y) until it is past the wall
(x > a + c / 2), then at the target (0.2, 0). The control is u = kp (waypoint - p) - kd v, scaled down as a whole
(direction kept) to |u_j| <= 0.99; the action is atanh(u) when the env squashes actions with tanh
(``env.action_transform``, the DMC default), u itself when it clips them.

The way is drawn where the ways part: at the start of an episode, which the demonstrator recognises from the
observation (at rest, x < -a: a reset state; moving, the mass is never exactly at rest there). Its action there has
two modes, one per way; their mean (``mean_of_ways``) pushes straight at the wall: on the axis (y = 0) the waypoints
(0, Y) and (0, -Y) give opposite y actions and equal x actions, so the averaged controller drives the mass into the
wall's middle and holds it there.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from tensordict import TensorDict

from refpo_warp.tasks.dmc.point_mass_wall_cfg import ARENA, TARGET_X, PointMassWallCfg
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Real
from refpo_warp.utils.options import option

KP, KD = 10.0, 1.0  # per metre of waypoint error, per m/s: closed loop 0.3 x'' + 1.1 x' + x = 0, about critical
MAX_CONTROL = 0.99  # atanh(0.99) = 2.65: the largest pre-tanh action
MAX_CLEARANCE = 0.05


@dataclass(frozen=True)
class Options:
    """The demonstrator's options: demonstrator.<option>=value on refpo collect's line."""

    left_share: float = option(
        0.6, Real(0, 1), "probability that an episode goes around the left (+y) end of the wall, else the right one"
    )


class Demonstrator:
    """obs -> actions (num_envs, 2) for dmc_point_mass_wall of env options ``cfg``; ways drawn with ``generator``."""

    def __init__(self, cfg: PointMassWallCfg, generator: torch.Generator, left_share: float = 0.6) -> None:
        self.generator, self.left_share = generator, float(left_share)
        self.tanh = cfg.action_transform == "tanh"
        self.a, self.b = cfg.wall_box()
        self.clearance = min(MAX_CLEARANCE, (ARENA - self.b) / 2)
        self.side: torch.Tensor | None = None  # the way of each env's episode: +1 left, -1 right

    def __call__(self, obs: TensorDict) -> torch.Tensor:
        x = obs["policy"]
        fresh = self.episode_starts(x)
        if self.side is None or self.side.shape[0] != x.shape[0]:
            self.side = torch.ones(x.shape[0], device=x.device)
            fresh = torch.ones_like(fresh)
        left = torch.rand(x.shape[0], generator=self.generator).to(x.device) < self.left_share
        self.side = torch.where(fresh, torch.where(left, 1.0, -1.0), self.side)
        return self.actions(x, self.side)

    def episode_starts(self, x: torch.Tensor) -> torch.Tensor:
        """Envs whose observation is a reset state: at rest before the wall."""
        return (x[:, 2:4] == 0).all(dim=-1) & (x[:, 0] < -self.a)

    def waypoints(self, x: torch.Tensor, side: torch.Tensor) -> torch.Tensor:
        """The waypoint (num_envs, 2) that way ``side`` (+1 left, -1 right per env) aims at from the positions."""
        a, b, c = self.a, self.b, self.clearance
        px, py = x[:, 0], x[:, 1]
        y = side * (b + c)
        beyond = side * py > b + c / 2
        past = px > a + c / 2
        wx = torch.where(past, TARGET_X, torch.where(beyond, a + c, 0.0))
        wy = torch.where(past, 0.0, y)
        return torch.stack([wx, wy], dim=-1)

    def controls(self, x: torch.Tensor, side: torch.Tensor) -> torch.Tensor:
        """The motor controls in [-0.99, 0.99] of way ``side``: PD on the waypoint, scaled down as a whole."""
        u = KP * (self.waypoints(x, side) - x[:, :2]) - KD * x[:, 2:4]
        scale = (MAX_CONTROL / u.abs().amax(dim=-1).clamp_min(1e-12)).clamp(max=1.0)
        return u * scale[:, None]

    def actions(self, x: torch.Tensor, side: torch.Tensor) -> torch.Tensor:
        """The policy's actions for way ``side``: pre-tanh (atanh of the controls) under the tanh transform."""
        u = self.controls(x, side)
        return torch.atanh(u) if self.tanh else u

    def mean_of_ways(self, x: torch.Tensor) -> torch.Tensor:
        """The mean of the left and right ways' actions at ``x`` (what averaging the two modes gives)."""
        left, right = torch.ones(x.shape[0], device=x.device), -torch.ones(x.shape[0], device=x.device)
        return 0.5 * (self.actions(x, left) + self.actions(x, right))

    def describe(self) -> dict:
        return {
            "kind": "scripted",
            "task_family": "dmc",
            "left_share": self.left_share,
            "kp": KP,
            "kd": KD,
            "rule": "per episode, left (+y) with probability left_share, else right; PD on waypoints: the middle of "
            "the gap beyond that end of the wall, then past the wall, then the target; tanh^-1 of the controls",
        }


def make_demonstrator(env_cfg, generator: torch.Generator, **options) -> Demonstrator:
    if not isinstance(env_cfg, PointMassWallCfg):
        raise ConfigError(
            f"task=dmc_{env_cfg.task} has no scripted demonstrator: the DMC family's (tasks/dmc/demonstrator.py) "
            "drives dmc_point_mass_wall only; collect from a trained run with run_dir=..."
        )
    return Demonstrator(env_cfg, generator, **options)
