"""Frames of GridWorld envs drawn with Pillow: the grid, its two goal bands (green), env i's trail since its episode
began and the agent (red)."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

GOAL, GRID, TRAIL, AGENT, FLOOR = (182, 227, 182), (215, 215, 215), (70, 110, 200), (214, 39, 40), (250, 250, 250)


class GridFrames:
    """``frame(i)`` of a ``GridWorldEnv``; it remembers each env's cells since its episode started."""

    def __init__(self, env, width: int, height: int, camera: str = "default", **_) -> None:
        if camera not in ("default", "fixed"):
            from refpo_warp.utils.errors import ConfigError

            raise ConfigError(f"camera={camera!r} is invalid for GridWorld; expected 'default' or 'fixed'")
        self.env, self.width, self.height = env, int(width), int(height)
        self.size = int(env.cfg.size)
        self.trails: dict[int, list[tuple[int, int]]] = {}
        self._lengths: dict[int, int] = {}
        self.control_hz = 10.0  # a grid move has no physical duration: ten moves a second

    def _cell_box(self, x: int, y: int) -> tuple[float, float, float, float]:
        side = min(self.width, self.height) / self.size
        left, top = (self.width - side * self.size) / 2, (self.height - side * self.size) / 2
        row = self.size - 1 - y  # y = 0 at the bottom
        return left + x * side, top + row * side, left + (x + 1) * side, top + (row + 1) * side

    def frame(self, i: int) -> tuple[np.ndarray, list[str]]:
        x, y = (int(v) for v in self.env.positions[i].tolist())
        length = int(self.env.episode_length_buf[i])
        if length < self._lengths.get(i, 0) or i not in self.trails:  # a new episode
            self.trails[i] = []
        self._lengths[i] = length
        self.trails[i].append((x, y))
        image = Image.new("RGB", (self.width, self.height), FLOOR)
        draw = ImageDraw.Draw(image)
        for cx in range(self.size):
            for cy in range(self.size):
                goal = cy in (0, 1, self.size - 2, self.size - 1)
                draw.rectangle(self._cell_box(cx, cy), fill=GOAL if goal else FLOOR, outline=GRID)
        centres = [((b[0] + b[2]) / 2, (b[1] + b[3]) / 2) for b in (self._cell_box(*c) for c in self.trails[i])]
        if len(centres) > 1:
            draw.line(centres, fill=TRAIL, width=max(2, self.width // 160))
        box = self._cell_box(x, y)
        pad = (box[2] - box[0]) * 0.15
        draw.ellipse((box[0] + pad, box[1] + pad, box[2] - pad, box[3] - pad), fill=AGENT)
        return np.asarray(image), [f"step {length}"]

    def close(self) -> None:
        pass


def frame_source(env, width: int, height: int, camera: str = "default", **_) -> GridFrames:
    return GridFrames(env, width, height, camera)
