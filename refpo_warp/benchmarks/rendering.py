"""Rendering speed: refpo bench render [width=640] [height=480] [timed_frames=60] [video_seconds=10]

Frames per second of each family's frames (a DMC task with its tracking camera, the humanoid with and without its
reference, GridWorld), drawn from envs stepped by uniform random actions, and the time to record and write a
``video_seconds`` long video of each (MP4, and GIF at half the size): the anchor of each row is the same frames without
the overlay, tiling and encoding, so the ratio says what a recording adds to drawing.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from refpo_warp.envs.registry import family_module, make_env
from refpo_warp.render.frames import overlay, tile
from refpo_warp.render.gl import select_gl_platform
from refpo_warp.render.video import write_video
from refpo_warp.utils.option_rules import Int, Real
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import print_table

CASES: tuple[tuple[str, dict[str, Any], dict[str, Any]], ...] = (
    ("dmc_cheetah_run", {}, {}),
    ("humanoid_all", {"eval_mode": True}, {"reference": True}),
    ("humanoid_all", {"eval_mode": True}, {"reference": False}),
    ("gridworld", {}, {}),
)


def frames_per_second(
    task: str, env_options: dict, render_options: dict, width: int, height: int, frames: int
) -> tuple[float, tuple[Any, Any]]:
    """Frames per second of drawing env 0 of ``task`` after each of ``frames`` random steps (the steps untimed), and
    (the env, its frame source)."""
    env = make_env(task, num_envs=1, device="cpu", seed=0, **env_options)
    source = family_module(task, "render").frame_source(env, width, height, **render_options)
    gen = torch.Generator().manual_seed(0)
    env.reset()
    source.frame(0)  # the first frame sets up the GL context and uploads the model
    seconds = 0.0
    for _ in range(frames):
        env.step(torch.rand(1, env.num_actions, generator=gen) * 2 - 1)
        start = time.perf_counter()
        source.frame(0)
        seconds += time.perf_counter() - start
    return frames / seconds, (env, source)


def video_seconds(env, source, fps: float, seconds: float, width: int, height: int) -> dict[str, float]:
    """Wall time to draw, overlay and write ``seconds`` of video at ``fps`` (MP4 at the size, GIF at half); the env
    steps between frames are not counted."""
    gen = torch.Generator().manual_seed(1)
    count = int(fps * seconds)
    drawn = 0.0
    frames = []
    for _ in range(count):
        env.step(torch.rand(1, env.num_actions, generator=gen) * 2 - 1)  # untimed, as above
        start = time.perf_counter()
        image, lines = source.frame(0)
        frames.append(tile([overlay(image, ["random agent", *lines])]))
        drawn += time.perf_counter() - start
    out = {"draw + overlay (s)": drawn}
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        path = write_video(frames, Path(tmp) / "bench.mp4", fps)
        out["MP4 write (s)"], out["MP4 (kB)"] = time.perf_counter() - start, path.stat().st_size / 1e3
        small = [f[::2, ::2] for f in frames]
        start = time.perf_counter()
        path = write_video(small, Path(tmp) / "bench.gif", fps)
        out["GIF write (s)"], out["GIF (kB)"] = time.perf_counter() - start, path.stat().st_size / 1e3
    return out


@dataclass(frozen=True)
class Options:
    width: int = option(640, Int(16, 8192), "frame width")
    height: int = option(480, Int(16, 8192), "frame height")
    timed_frames: int = option(60, Int(1), "timed frames per case")
    video_seconds: float = option(10.0, Real(0, 3600, lo_open=True), "length of the timed video, at 30 frames/s")


def run(args: Options, _: dict | None = None) -> None:
    platform = select_gl_platform()
    rows = []
    for task, env_options, render_options in CASES:
        fps, (env, source) = frames_per_second(
            task, env_options, render_options, args.width, args.height, args.timed_frames
        )
        row = {
            "frames": f"{task}"
            + ("" if not render_options else f" (reference {'on' if render_options['reference'] else 'off'})"),
            "frames/s": f"{fps:.1f}",
        }
        video = video_seconds(env, source, 30.0, args.video_seconds, args.width, args.height)
        anchor = args.video_seconds * 30 / fps  # drawing alone
        row.update({k: f"{v:.2f}" if "(s)" in k else f"{v:.0f}" for k, v in video.items()})
        row["video / drawing"] = f"{(video['draw + overlay (s)'] + video['MP4 write (s)']) / anchor:.2f}"
        source.close()
        rows.append(row)
    print_table(
        rows,
        list(rows[0]),
        title=f"Rendering on the CPU ({platform}), {args.width}x{args.height}, shadows "
        f"off; {args.video_seconds:g} s videos at 30 frames/s",
    )
