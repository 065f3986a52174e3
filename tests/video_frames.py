"""Reading a written video back, for the tests that check what a command recorded."""

from pathlib import Path

import numpy as np


def read_video(path: str | Path) -> np.ndarray:
    """All frames of an MP4 or GIF file as (frames, height, width, 3) uint8 ."""
    import imageio.v2 as imageio

    return np.stack([np.asarray(f)[..., :3] for f in imageio.mimread(str(path), memtest=False)])
