"""Demonstration datasets: the round trip through Minari's format (ours and Minari's own reader), the spaces check,
and every damaged or foreign file refused with one message naming it, without running anything it names."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

pytest.importorskip("minari")

from dataset_helpers import damage, edit_metadata, episode, write

from refpo_warp.demonstrations.dataset_file import check_spaces, read_dataset
from refpo_warp.utils.errors import ConfigError, DataFileError


def test_round_trip_keeps_every_array_and_the_metadata(tmp_path):
    episodes = [episode(5, seed=1), episode(3, seed=2, terminated=False)]
    path = write(tmp_path / "data", episodes)
    data = read_dataset(path)
    assert (data.obs_dim, data.action_dim, len(data.episodes)) == (2, 2, 2)
    for got, want in zip(data.episodes, episodes):
        for key in ("observations", "actions", "rewards", "terminations", "truncations"):
            np.testing.assert_array_equal(getattr(got, key), getattr(want, key))
    assert data.refpo == {"task": "gridworld", "policy": {"algo": "scripted"}}
    obs, actions = data.transitions()
    np.testing.assert_array_equal(obs, np.concatenate([e.observations[:-1] for e in episodes]))
    np.testing.assert_array_equal(actions, np.concatenate([e.actions for e in episodes]))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp folder left


def test_minari_reads_what_we_write(tmp_path):
    import minari

    dataset = minari.MinariDataset(write(tmp_path / "data"))
    assert dataset.total_episodes == 2 and dataset.total_steps == 8
    assert dataset.observation_space.shape == (2,) and dataset.action_space.shape == (2,)
    first = next(iter(dataset))
    assert first.observations.shape == (6, 2) and bool(first.terminations[-1])


def test_a_dataset_made_by_minari_loads(tmp_path):
    """Written by Minari's own API (no refpo metadata): it loads, and its spaces are checked against the task's."""
    import gymnasium as gym
    from minari.data_collector.episode_buffer import EpisodeBuffer
    from minari.dataset.minari_storage import MinariStorage

    box = gym.spaces.Box(-1, 1, shape=(2,), dtype=np.float32)
    storage = MinariStorage.new(tmp_path / "other", observation_space=box, action_space=box)
    e = episode(4)
    storage.update_episodes(
        [
            EpisodeBuffer(
                id=0,
                observations=e.observations,
                actions=e.actions,
                rewards=e.rewards,
                terminations=e.terminations,
                truncations=e.truncations,
                infos={},
            )
        ]
    )
    data = read_dataset(tmp_path / "other")
    check_spaces(data, "gridworld", 2, 2)
    with pytest.raises(DataFileError, match=r"observation dim 2, action dim 2.*observation dim 3, action dim 2"):
        check_spaces(data, "dmc_point_mass", 3, 2)


def test_spaces_of_another_task_are_refused(tmp_path):
    data = read_dataset(write(tmp_path / "data"))
    with pytest.raises(DataFileError, match="recorded on task gridworld; this run's task is dmc_point_mass"):
        check_spaces(data, "dmc_point_mass", 2, 2)


def test_an_existing_dataset_is_kept_unless_overwrite(tmp_path):
    path = write(tmp_path / "data")
    before = (path / "metadata.json").read_text()
    with pytest.raises(ConfigError, match="overwrite=true"):
        write(path, [episode(9, seed=5)])
    assert (path / "metadata.json").read_text() == before
    write(path, [episode(9, seed=5)], overwrite=True)
    assert [e.length for e in read_dataset(path).episodes] == [9]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data"]


@pytest.mark.parametrize(
    "kind,culprit",
    [
        ("missing", "no such dataset"),
        ("file", "found a file"),
        ("not JSON", "not readable as JSON"),
        ("unknown format", "unknown or unsupported data_format 'arrow'"),
        ("empty", "holds no episode"),
        ("NaN", "'actions' holds 1 NaN or infinite"),
        ("inf", "'observations' holds 1 NaN or infinite"),
        ("truncated mid-episode", "truncated mid-episode"),
        ("damaged hdf5", "cannot be read as a Minari dataset"),
    ],
)
def test_bad_datasets_are_refused_naming_the_file(tmp_path, kind, culprit):
    path = damage(kind, write(tmp_path / "data"))
    with pytest.raises(DataFileError, match=culprit) as err:
        read_dataset(path)
    assert str(path.name) in str(err.value)


def test_reading_never_imports_what_the_file_names(tmp_path):
    """Without both spaces Minari would gym.make() the env spec the file names (importing its module): refused."""
    path = write(tmp_path / "data")
    marker = tmp_path / "ran"
    (tmp_path / "evil_env.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    sys.path.insert(0, str(tmp_path))
    try:
        spec = json.dumps({"id": "Evil-v0", "entry_point": "evil_env:Env", "kwargs": {}})
        edit_metadata(path, observation_space=None, env_spec=spec)
        with pytest.raises(DataFileError, match="names no observation_space"):
            read_dataset(path)
    finally:
        sys.path.remove(str(tmp_path))
    assert not marker.exists() and "evil_env" not in sys.modules
