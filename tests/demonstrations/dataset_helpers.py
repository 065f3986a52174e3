"""Helpers of tests/demonstrations: small datasets written through refpo_warp's writer or Minari's own API (as one
made elsewhere), and the ways a file gets damaged."""

from __future__ import annotations

import json

import numpy as np

from refpo_warp.demonstrations.dataset_file import Episode, write_dataset


def episode(length: int, obs_dim: int = 2, action_dim: int = 2, seed: int = 0, terminated: bool = True) -> Episode:
    rng = np.random.default_rng(seed)
    ends = np.zeros(length, bool)
    ends[-1] = True
    return Episode(
        rng.normal(size=(length + 1, obs_dim)).astype(np.float32),
        rng.uniform(-1, 1, size=(length, action_dim)).astype(np.float32),
        rng.normal(size=length).astype(np.float32),
        ends if terminated else np.zeros(length, bool),
        np.zeros(length, bool) if terminated else ends,
    )


def write(path, episodes=None, task="gridworld", **kw):
    """Two GridWorld-shaped episodes (one terminated, one truncated) unless ``episodes``; ``task=None``: a dataset
    that names no task (as one made elsewhere)."""
    episodes = episodes if episodes is not None else [episode(5, seed=1), episode(3, seed=2, terminated=False)]
    obs_dim, action_dim = episodes[0].observations.shape[1], episodes[0].actions.shape[1]
    refpo = {"policy": {"algo": "scripted"}} if task is None else {"task": task, "policy": {"algo": "scripted"}}
    return write_dataset(path, episodes, obs_dim, action_dim, 1.0, refpo, **kw)


def minari_dataset(path, episodes, action_low=-1.0, action_high=1.0):
    """``episodes`` written by Minari's own API (no refpo entry: a dataset made elsewhere), its action space
    ``Box(action_low, action_high)`` and an unbounded observation space."""
    import gymnasium as gym
    from minari.data_collector.episode_buffer import EpisodeBuffer
    from minari.dataset.minari_storage import MinariStorage

    obs_dim, action_dim = episodes[0].observations.shape[1], episodes[0].actions.shape[1]
    obs_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_dim,), dtype=np.float32)
    action_space = gym.spaces.Box(action_low, action_high, shape=(action_dim,), dtype=np.float32)
    storage = MinariStorage.new(path, observation_space=obs_space, action_space=action_space)
    storage.update_episodes(
        EpisodeBuffer(
            id=i,
            observations=e.observations,
            actions=e.actions,
            rewards=e.rewards,
            terminations=e.terminations,
            truncations=e.truncations,
            infos={},
        )
        for i, e in enumerate(episodes)
    )
    return path


def with_actions(e: Episode, actions) -> Episode:
    """``e`` holding ``actions`` (a list of rows, one per step) instead of its own."""
    actions = np.asarray(actions, np.float32)
    assert actions.shape == e.actions.shape
    return Episode(e.observations, actions, e.rewards, e.terminations, e.truncations)


def edit_metadata(path, **changes):
    meta = json.loads((path / "metadata.json").read_text())
    for key, value in changes.items():
        if value is None:
            meta.pop(key, None)
        else:
            meta[key] = value
    (path / "metadata.json").write_text(json.dumps(meta))


def rewrite_episode(path, key, transform):
    import h5py

    with h5py.File(path / "main_data.hdf5", "a") as f:
        values = transform(f["episode_0"][key][()])
        del f["episode_0"][key]
        f["episode_0"][key] = values


def damage(kind, path):
    """Damage the dataset at ``path`` in the way ``kind`` names; returns the path to hand over."""
    if kind == "missing":
        return path.parent / "nowhere"
    if kind == "file":
        target = path.parent / "data.hdf5"
        target.write_bytes(b"\x89HDF\r\n")
        return target
    if kind == "not JSON":
        (path / "metadata.json").write_text("{not json")
    elif kind == "unknown format":
        edit_metadata(path, data_format="arrow")
    elif kind == "empty":
        import h5py

        with h5py.File(path / "main_data.hdf5", "a") as f:
            for name in list(f):
                del f[name]
        edit_metadata(path, total_episodes=0, total_steps=0)
    elif kind == "NaN":
        rewrite_episode(path, "actions", lambda a: np.where(np.arange(a.size).reshape(a.shape) == 3, np.nan, a))
    elif kind == "inf":
        rewrite_episode(path, "observations", lambda a: np.where(np.arange(a.size).reshape(a.shape) == 1, np.inf, a))
    elif kind == "truncated mid-episode":
        for key in ("actions", "rewards", "terminations", "truncations"):
            rewrite_episode(path, key, lambda a: a[:-1])
        rewrite_episode(path, "observations", lambda a: a[:-1])
    elif kind == "damaged hdf5":
        data = path / "main_data.hdf5"
        data.write_bytes(data.read_bytes()[:200])
    return path
