"""Demonstration datasets: the round trip through Minari's format (ours and Minari's own reader), the spaces check,
and every damaged or foreign file refused with one message naming it, without running anything it names."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

pytest.importorskip("minari")

from dataset_helpers import damage, edit_metadata, episode, minari_dataset, rewrite_episode, write

from refpo_warp.demonstrations.dataset_file import REFPO_KEY, check_spaces, env_differences, read_dataset
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
    """Written by Minari's own API (no refpo metadata): it loads, with its action space's bounds, and its spaces are
    checked against the task's."""
    e = episode(4)
    data = read_dataset(minari_dataset(tmp_path / "other", [e], action_low=-1.0, action_high=1.0))
    assert data.refpo == {}
    np.testing.assert_array_equal(data.episodes[0].actions, e.actions)
    assert data.action_low.tolist() == [-1.0, -1.0] and data.action_high.tolist() == [1.0, 1.0]
    check_spaces(data, "gridworld", 2, 2)
    with pytest.raises(DataFileError, match=r"observation dim 2, action dim 2.*observation dim 3, action dim 2"):
        check_spaces(data, "dmc_point_mass", 3, 2)
    unbounded = read_dataset(minari_dataset(tmp_path / "unbounded", [e], action_low=-np.inf, action_high=np.inf))
    assert np.isinf(unbounded.action_low).all() and np.isinf(unbounded.action_high).all()


def test_spaces_of_another_task_are_refused(tmp_path):
    data = read_dataset(write(tmp_path / "data"))
    with pytest.raises(DataFileError, match="recorded on task gridworld; this run's task is dmc_point_mass"):
        check_spaces(data, "dmc_point_mass", 2, 2)


def test_env_differences_name_each_option_that_differs_from_the_runs_env(tmp_path):
    data = read_dataset(write(tmp_path / "data"))
    data.metadata[REFPO_KEY] = {"task": "dmc_point_mass_wall", "env": {"start_spread": 0.0, "wall_half_length": 0.2}}
    task = "dmc_point_mass_wall"
    assert env_differences(data, task, {"start_spread": 0.0, "wall_half_length": 0.2}) == []
    assert env_differences(data, task, {"start_spread": 0.0}) == [
        "env.wall_half_length: 0.2 in the dataset, 0.15 here"  # the task's default wall
    ]
    data.metadata[REFPO_KEY]["env"] = {"wall_lenght": 0.2}
    with pytest.raises(DataFileError, match=r"data: its env options \{'wall_lenght': 0.2\} are not task"):
        env_differences(data, task, {})


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


NON_NUMERIC = {
    "bytes": (lambda a: np.full(a.shape, b"0.5"), "|S3", "bytes"),
    "text": (lambda a: np.array([str(x) for x in a.ravel()], object).reshape(a.shape), "object", "Python objects"),
    "complex": (lambda a: a.astype(np.complex64), "complex64", "complex numbers"),
}


@pytest.mark.parametrize("key", ["observations", "actions", "rewards", "terminations", "truncations"])
@pytest.mark.parametrize("kind", list(NON_NUMERIC))
def test_an_array_of_no_numbers_is_refused_naming_it_its_episode_and_dtype(tmp_path, key, kind):
    """Bytes, text (h5py reads variable-length strings as Python objects) or complex numbers, even where they would
    convert to floats ('0.5'): refused before any arithmetic touches them."""
    transform, dtype, what = NON_NUMERIC[kind]
    path = write(tmp_path / "data")
    rewrite_episode(path, key, transform)
    with pytest.raises(DataFileError) as err:
        read_dataset(path)
    assert str(err.value) == (
        f"{path}: episode 0: '{key}' holds {dtype} values ({what}); a dataset's arrays hold numbers (bool, integer "
        f"or float)"
    )


def test_integer_and_bool_arrays_are_numbers(tmp_path):
    path = write(tmp_path / "data")
    rewrite_episode(path, "rewards", lambda a: np.arange(len(a), dtype=np.int16))
    rewrite_episode(path, "terminations", lambda a: a.astype(np.uint8))
    rewrite_episode(path, "observations", lambda a: (a > 0).astype(bool))
    data = read_dataset(path)
    assert data.episodes[0].rewards.tolist() == [0, 1, 2, 3, 4] and bool(data.episodes[0].terminations[-1])


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
