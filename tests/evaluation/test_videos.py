"""A training run records its final policy when asked (video.at_end), lists the video in its summary, and the
recording leaves the run's random streams as they were."""

import numpy as np
import torch
from video_frames import read_video  # tests/ is on sys.path under pytest

from refpo_warp.training import train
from refpo_warp.utils.rng import own_random_streams


def test_a_run_records_its_final_policy_and_lists_the_video(tmp_run_dir, capsys):
    results = train(
        [
            "task=gridworld",
            "algo=refpo",
            "device=cpu",
            "max_iterations=1",
            "num_envs=8",
            "runner.num_steps_per_env=8",
            "algorithm.num_mc_samples=2",
            "eval.num_envs=8",
            "eval.interval=0",
            "video.at_end=true",
            "video.width=64",
            "video.height=48",
            "video.length=4",
            f"run_dir={tmp_run_dir}",
        ]
    )
    video = tmp_run_dir / "videos" / "final.mp4"
    assert results["videos"] == [str(video)] and read_video(video).shape[1:] == (48, 64, 3)
    assert f"videos        {video}" in capsys.readouterr().out.replace(f"{video.parent}/{{final.mp4}}", str(video))


def test_a_recording_leaves_the_random_streams_alone():
    torch.manual_seed(1)
    np.random.seed(1)
    expected = torch.rand(2), np.random.rand(2)
    torch.manual_seed(1)
    np.random.seed(1)
    with own_random_streams(7):
        inside = torch.rand(2)
        torch.rand(100)
        np.random.rand(100)
    assert torch.equal(torch.rand(2), expected[0]) and np.array_equal(np.random.rand(2), expected[1])
    with own_random_streams(7):  # the block's own draws depend on its seed alone
        assert torch.equal(torch.rand(2), inside)
