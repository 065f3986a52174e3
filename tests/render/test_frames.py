"""Frames: drawn from the env's state (not blank, changing with it), the humanoid's reference where it differs from
the body, tiles and overlays, and MP4 / GIF files that read back with their frame count and size."""

import numpy as np
import pytest
import torch
from video_frames import read_video  # tests/ is on sys.path under pytest

from refpo_warp import make_env
from refpo_warp.render.frames import overlay, tile
from refpo_warp.render.video import write_video

W, H = 96, 72


def test_dmc_frames_show_each_envs_state_and_follow_it():
    from refpo_warp.tasks.dmc.render import frame_source

    env = make_env("dmc_cartpole_balance", num_envs=2, device="cpu", seed=0)
    env.set_state(torch.tensor([[0.0, 0.0], [0.8, 1.2]]), torch.zeros(2, 2))  # cart at 0 upright; moved and tilted
    frames = frame_source(env, W, H)
    try:
        first, second = frames.frame(0)[0], frames.frame(1)[0]
        assert first.shape == (H, W, 3) and first.dtype == np.uint8 and first.std() > 10  # drawn, not blank
        assert (np.abs(first.astype(int) - second).sum(axis=-1) > 30).mean() > 0.003  # two states, two pictures
        env.set_state(torch.tensor([[0.8, 1.2], [0.8, 1.2]]), torch.zeros(2, 2))
        assert np.array_equal(frames.frame(0)[0], second)  # env 0 now in env 1's state: the same picture
    finally:
        frames.close()


def test_the_humanoids_reference_is_drawn_where_it_is():
    from refpo_warp.tasks.humanoid.render import HumanoidFrames

    env = make_env("humanoid_all", num_envs=1, device="cpu", seed=0)
    env.reset()
    for _ in range(15):  # zero actions: the body leaves the reference
        env.step(torch.zeros(1, env.num_actions))
    with_ref, without = HumanoidFrames(env, W, H), HumanoidFrames(env, W, H, reference=False)
    try:
        (a, lines), (b, _) = with_ref.frame(0), without.frame(0)
        assert a.std() > 10 and b.std() > 10
        changed = np.abs(a.astype(int) - b).sum(axis=-1) > 30
        assert changed.mean() > 0.004  # the stick figure covers part of the frame
        tint = lambda img: img[changed][:, 2].astype(int) - img[changed][:, 0]  # noqa: E731  (blue minus red)
        assert (tint(a) > tint(b)).mean() > 0.9  # drawn in the reference's translucent blue
        assert lines[0].startswith("clip ") and lines[1].startswith("MPJPE ") and float(lines[1].split()[1]) > 0
    finally:
        with_ref.close()
        without.close()


def test_grid_frames_draw_the_agent_and_its_trail():
    from refpo_warp.tasks.gridworld.render import frame_source

    env = make_env("gridworld", num_envs=1, device="cpu", seed=0)
    env.reset_to(torch.tensor([[12, 12]]))
    frames = frame_source(env, W, H)
    a = frames.frame(0)[0]
    env.step(torch.tensor([[1.0, 0.0]]))
    b = frames.frame(0)[0]
    assert a.shape == (H, W, 3) and not np.array_equal(a, b)  # the agent moved right


def test_tiles_and_overlays():
    frames = [np.full((4, 6, 3), v, np.uint8) for v in (10, 20, 30)]
    grid = tile(frames)
    assert grid.shape == (8, 12, 3) and grid[0, 0, 0] == 10 and grid[0, 6, 0] == 20 and grid[4, 0, 0] == 30
    assert tile(frames, columns=3).shape == (4, 18, 3)
    image = np.zeros((72, 96, 3), np.uint8)
    written = overlay(image, ["N=1  return 12.0"])
    assert written[:16, :60].max() > 100 and written[40:].max() == 0  # text top left only


@pytest.mark.parametrize("fmt", ["mp4", "gif"])
def test_videos_read_back_with_their_frame_count_and_size(tmp_path, fmt):
    frames = [np.full((H, W, 3), 30 * k, np.uint8) for k in range(7)]
    path = write_video(frames, tmp_path / f"clip.{fmt}", fps=10)
    video = read_video(path)
    assert video.shape == (7, H, W, 3)
    assert abs(float(video[3].mean()) - 90) < 8  # the frames in order (lossy codecs keep their brightness)
    assert not list(tmp_path.glob(".*.tmp"))  # written through a temp file


def test_a_gif_keeps_every_kth_frame_above_50_per_second(tmp_path):
    frames = [np.full((8, 8, 3), k, np.uint8) for k in range(10)]
    assert read_video(write_video(frames, tmp_path / "fast.gif", fps=100)).shape[0] == 5
    with pytest.raises(ValueError, match="video format"):
        write_video(frames, tmp_path / "clip.avi", fps=10)
