"""dmc_point_mass_wall's env options and its arena's fixed geometry (Warp-free), shared by the task
(``suite/point_mass_wall.py``), its scripted demonstrator (``demonstrator.py``) and the figure script
(``docs/figures/draw_point_mass_wall.py``).

The arena is point_mass's: the mass's centre moves in [-0.29, 0.29]^2 (the slide joints' limits). The mass starts
at (START_X, 0) = (-0.2, 0) (plus ``start_spread``), the target sits at (TARGET_X, 0) = (0.2, 0), and a wall across
the middle (a box centred on the origin, along y) blocks the straight path between them; the mass passes around
either end, left (+y, seen from the start) or right (-y).
"""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.tasks.dmc.cfg import DmcCfg
from refpo_warp.utils.option_rules import Num, Real
from refpo_warp.utils.options import option

ARENA = 0.29  # the mass's centre stays in [-ARENA, ARENA]^2 (the joint range; the floor's edge is at 0.3)
MASS_RADIUS = 0.01
START_X = -0.2
TARGET_X = 0.2
TARGET_RADIUS = 0.015
PATH_MARGIN = 1.0  # the progress term falls linearly to 0 over this path length beyond the target's radius
MIN_WALL_HALF_LENGTH = 0.05  # above start_spread's bound + MASS_RADIUS: the straight path is always blocked
MAX_WALL_HALF_LENGTH = 0.25  # leaves gaps of 0.05 (2.5 mass diameters) to the arena's edge, ARENA + MASS_RADIUS
MAX_START_SPREAD = 0.03


class WallHalfLength(Num):
    """A number in [MIN_WALL_HALF_LENGTH, MAX_WALL_HALF_LENGTH]; the error says what a wall out of the range would
    do: close (or almost close) the arena, or leave the straight path open."""

    def __init__(self) -> None:
        super().__init__(MIN_WALL_HALF_LENGTH, MAX_WALL_HALF_LENGTH)

    def _check(self, key: str, raw):
        if isinstance(raw, (int, float)) and not isinstance(raw, bool) and raw > MAX_WALL_HALF_LENGTH:
            gap = ARENA + MASS_RADIUS - raw  # between the wall's end and the arena's edge
            why = (
                "the wall would close the arena (no gap at its ends wider than the mass)"
                if gap <= 2 * MASS_RADIUS + 1e-9
                else f"the gaps at the wall's ends would be {gap:.3g} wide, under the "
                f"{ARENA + MASS_RADIUS - MAX_WALL_HALF_LENGTH:.2g} the task keeps for the mass (diameter "
                f"{2 * MASS_RADIUS:g})"
            )
            raise self.error(key, raw, why)
        if isinstance(raw, (int, float)) and not isinstance(raw, bool) and raw < MIN_WALL_HALF_LENGTH:
            raise self.error(key, raw, "the wall would not block every start's straight path to the target")
        return super()._check(key, raw)


@dataclass
class PointMassWallCfg(DmcCfg):
    wall_half_length: float = option(
        0.15,
        WallHalfLength(),
        "half the wall's length across the arena: it spans y in [-L, L] at x = 0, leaving gaps of 0.3 - L to the "
        "arena's edge for the mass (diameter 0.02) to pass; 0.28 closes the arena; at most 0.25 (gaps of 2.5 "
        "diameters), at least 0.05 (a shorter wall would not block the straight path)",
    )
    wall_half_thickness: float = option(
        0.02,
        Real(0.005, 0.1),
        "half the wall's thickness along x (the wall's faces at x = -T and T; the mass moves under 3 mm a step, so "
        "it cannot tunnel)",
    )
    start_spread: float = option(
        0.02,
        Real(0.0, MAX_START_SPREAD),
        "the start is (-0.2 + U(-s, s), U(-s, s)) at rest: s, the spread around the wall's axis",
    )

    def wall_box(self) -> tuple[float, float]:
        """(a, b): the half-sizes of the region the mass's centre cannot enter (the wall grown by the mass's radius)."""
        return self.wall_half_thickness + MASS_RADIUS, self.wall_half_length + MASS_RADIUS
