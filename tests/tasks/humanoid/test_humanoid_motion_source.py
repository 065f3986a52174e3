"""The tracking env's ``motion_file`` option: "" is every shipped clip, ``shipped:<file>`` one of them wherever the
package is installed (not a path into a checkout), anything else a path."""

import pytest

from refpo_warp.config.resolve import resolve_config
from refpo_warp.tasks.humanoid.motions import SHIPPED_MOTIONS, num_clips, resolve_motion_file
from refpo_warp.utils.errors import ConfigError


def test_empty_is_every_shipped_clip_and_shipped_names_one():
    assert resolve_motion_file("") == SHIPPED_MOTIONS
    assert num_clips("") == 12
    assert resolve_motion_file("shipped:stand_sway_poses.npz") == SHIPPED_MOTIONS / "stand_sway_poses.npz"
    assert num_clips("shipped:stand_sway_poses.npz") == 1


def test_a_path_is_taken_from_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert resolve_motion_file("clips/a_poses.npz") == tmp_path / "clips" / "a_poses.npz"
    assert resolve_motion_file("~/x.npz").is_absolute()


def test_an_unknown_shipped_name_lists_the_shipped_clips():
    with pytest.raises(
        ConfigError,
        match=r"motion_file=shipped:<file> 'stand_sway_pose\.npz'.*Did you mean "
        r"'stand_sway_poses\.npz'.*wave_right_poses\.npz",
    ):
        resolve_motion_file("shipped:stand_sway_pose.npz")


@pytest.mark.parametrize("task", ["humanoid_root", "humanoid_all", "humanoid_all_residual"])
def test_the_shipped_humanoid_profiles_find_their_motions_from_any_directory(task, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for device in ("cpu", "cuda"):
        motion_file = resolve_config([f"task={task}"], device_type=device)["env"].get("motion_file", "")  # "": default
        assert resolve_motion_file(motion_file).exists(), (task, device, motion_file)
