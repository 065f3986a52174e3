"""Video files from frames: MP4 (H.264 through the ffmpeg binary of the ``imageio-ffmpeg`` wheel) and GIF (Pillow),
each written to a temp file and renamed, so a reader never sees half a video.

GIF frames hold whole hundredths of a second and browsers slow anything under 2/100 s down to 10/100 s, so a GIF
plays at most 50 frames per second (``GIF_MAX_FPS``); ``write_video`` keeps every k-th frame to stay under it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from refpo_warp.utils.atomic_files import atomic_path, atomic_write

FORMATS = ("mp4", "gif")
GIF_MAX_FPS = 50


def write_mp4(frames: list[np.ndarray], path: Path, fps: float) -> Path:
    """H.264 MP4 (yuv420p; frame sizes cut to even numbers, which the encoder needs)."""
    import imageio_ffmpeg

    h, w = frames[0].shape[:2]
    h2, w2 = h - h % 2, w - w % 2
    with atomic_path(path) as tmp:
        writer = imageio_ffmpeg.write_frames(
            str(tmp),
            (w2, h2),
            fps=fps,
            codec="libx264",
            quality=7,
            pix_fmt_out="yuv420p",
            macro_block_size=1,
            ffmpeg_log_level="error",
            output_params=["-f", "mp4"],
        )
        writer.send(None)  # start ffmpeg
        try:
            for frame in frames:
                writer.send(np.ascontiguousarray(frame[:h2, :w2]))
        finally:
            writer.close()
    return path


def write_gif(frames: list[np.ndarray], path: Path, fps: float) -> Path:
    """An endlessly looping GIF (adaptive palette per frame)."""
    from PIL import Image

    images = [Image.fromarray(frame) for frame in frames]
    with atomic_write(path) as f:
        images[0].save(
            f,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            loop=0,
            duration=max(20, round(1000 / fps / 10) * 10),
            optimize=False,
        )
    return path


def write_video(frames: list[np.ndarray], path: str | Path, fps: float) -> Path:
    """``frames`` as ``path`` (its suffix, .mp4 or .gif, names the format) at ``fps`` frames per second."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    if fmt not in FORMATS:
        raise ValueError(f"video format must be one of {FORMATS}, got {path.suffix!r}")
    if not frames:
        raise ValueError("no frames to write")
    path.parent.mkdir(parents=True, exist_ok=True)
    if fmt == "mp4":
        return write_mp4(frames, path, fps)
    keep = max(1, math.ceil(fps / GIF_MAX_FPS))
    return write_gif(frames[::keep], path, fps / keep)
