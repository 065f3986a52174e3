"""Frames as arrays: a text overlay (a dark band with white lines), a title above a panel, panels tiled in a grid."""

from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

BACKGROUND = (20, 20, 24)


def _font(height: int):
    return ImageFont.load_default(size=max(10, height // 32))


def overlay(frame: np.ndarray, lines: list[str]) -> np.ndarray:
    """``frame`` with ``lines`` written top left on a translucent dark band."""
    if not lines:
        return frame
    image = Image.fromarray(frame).convert("RGBA")
    band = Image.new("RGBA", image.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(band)
    font = _font(frame.shape[0])
    line_height = font.getbbox("Ag")[3] + 4
    width = max(draw.textlength(line, font=font) for line in lines) + 12
    draw.rectangle((0, 0, width, 6 + line_height * len(lines)), fill=(0, 0, 0, 150))
    for k, line in enumerate(lines):
        draw.text((6, 4 + k * line_height), line, fill=(255, 255, 255, 255), font=font)
    return np.asarray(Image.alpha_composite(image, band).convert("RGB"))


def tile(frames: list[np.ndarray], columns: int | None = None) -> np.ndarray:
    """Same-size frames in a grid (row-major), ``columns`` wide (default: as square as the count allows)."""
    if not frames:
        raise ValueError("tile() needs at least one frame")
    h, w, c = frames[0].shape
    columns = columns or math.ceil(math.sqrt(len(frames)))
    rows = math.ceil(len(frames) / columns)
    out = np.empty((rows * h, columns * w, c), dtype=frames[0].dtype)
    out[:] = BACKGROUND
    for k, frame in enumerate(frames):
        r, q = divmod(k, columns)
        out[r * h : (r + 1) * h, q * w : (q + 1) * w] = frame
    return out
