"""Demonstration datasets in Minari's format (the gymnasium ecosystem's offline-RL standard): write, read, check.

A dataset is a folder: ``metadata.json`` (the observation and action spaces as Minari serialises them, the episode and
step counts, and our ``refpo`` entry: the task, its env options and the policy that made the data) and
``main_data.hdf5`` with one group per episode: ``observations`` (T + 1 rows: the last is the state the episode
ended in), ``actions``, ``rewards``, ``terminations`` and ``truncations`` (T rows each). Minari's own
``MinariDataset(path)`` reads what ``write_dataset`` writes, and ``read_dataset`` reads a Minari dataset made
elsewhere (its spaces are checked against the task's by ``check_spaces``).

Reading never runs code from the file: the metadata is JSON and must name both spaces (Minari itself would otherwise
``gym.make`` the environment the file names, importing its module), only the ``hdf5`` format is accepted (no pickle
anywhere in it), and every array is checked (numbers: bool, integer or float; finite; shapes; each episode ending in a
termination or a truncation) before anything uses it. Every problem is one ``DataFileError`` naming the file (exit 4).
What the actions are (the policy's own or the env's, on a task that squashes them with tanh) is
``dataset_actions``'s question.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from refpo_warp.envs.registry import make_env_cfg
from refpo_warp.utils.errors import ConfigError, DataFileError

METADATA_FILE = "metadata.json"
DATA_FORMAT = "hdf5"  # the one Minari storage whose reader needs no optional package and holds no pickled objects
REFPO_KEY = "refpo"  # our entry in metadata.json: task, env options, the policy that made the data
MINARI_HINT = 'pip install "refpo-warp[data]" (Minari with its HDF5 storage)'


@dataclass
class Episode:
    """One episode: ``observations`` (T + 1, obs_dim), ``actions`` (T, action_dim), ``rewards``, ``terminations``,
    ``truncations`` (T,)."""

    observations: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray

    @property
    def length(self) -> int:
        return len(self.rewards)


@dataclass
class Dataset:
    """A dataset read and checked by ``read_dataset``."""

    path: Path
    episodes: list[Episode]
    obs_dim: int
    action_dim: int
    metadata: dict = field(default_factory=dict)
    action_low: np.ndarray | None = None  # the bounds of the action space the file records (float64; may be inf)
    action_high: np.ndarray | None = None

    @property
    def refpo(self) -> dict:
        """Our metadata entry (task, env options, policy), ``{}`` for a dataset made elsewhere."""
        entry = self.metadata.get(REFPO_KEY)
        return entry if isinstance(entry, dict) else {}

    @property
    def num_steps(self) -> int:
        return sum(e.length for e in self.episodes)

    def transitions(self, episode_indices=None) -> tuple[np.ndarray, np.ndarray]:
        """(observations, actions) of every step of the chosen episodes: the observation each action was taken in."""
        chosen = [self.episodes[i] for i in (range(len(self.episodes)) if episode_indices is None else episode_indices)]
        obs = np.concatenate([e.observations[:-1] for e in chosen]).astype(np.float32)
        actions = np.concatenate([e.actions for e in chosen]).astype(np.float32)
        return obs, actions


def _minari():
    try:
        from minari.dataset.minari_storage import MinariStorage
    except ImportError:
        raise ConfigError(f"demonstration datasets need Minari, which is not installed: {MINARI_HINT}") from None
    return MinariStorage


def box_spaces(obs_dim: int, action_dim: int, action_bound: float):
    """The gymnasium Box spaces of a task (float32; the action bound is inf where the env squashes with tanh)."""
    import gymnasium as gym

    obs = gym.spaces.Box(-np.inf, np.inf, shape=(obs_dim,), dtype=np.float32)
    action = gym.spaces.Box(-action_bound, action_bound, shape=(action_dim,), dtype=np.float32)
    return obs, action


def write_dataset(
    path: str | Path,
    episodes: list[Episode],
    obs_dim: int,
    action_dim: int,
    action_bound: float,
    refpo: dict,
    overwrite: bool = False,
) -> Path:
    """Write ``episodes`` as a Minari dataset folder at ``path``, atomically: built in a temp folder beside it, then
    renamed into place, so ``path`` is the old dataset or the new one, never a part. An existing ``path`` is refused
    unless ``overwrite``."""
    storage_class = _minari()
    path = Path(path).absolute()  # Minari's HDF5 storage joins a relative folder to itself
    if path.exists() and not overwrite:
        raise ConfigError(f"out={path} exists; pass overwrite=true to replace it, or choose another out")
    if path.exists() and not path.is_dir():
        raise ConfigError(f"out={path} is a file; a dataset is a folder: choose another out")
    if not episodes:
        raise ConfigError("no episode to write (episodes=0?)")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp"))
    os.chmod(tmp, 0o755)  # mkdtemp creates 0700; a dataset is shared like any written folder
    try:
        obs_space, action_space = box_spaces(obs_dim, action_dim, action_bound)
        storage = storage_class.new(
            tmp, observation_space=obs_space, action_space=action_space, data_format=DATA_FORMAT
        )
        storage.update_episodes(_buffer(i, e) for i, e in enumerate(episodes))
        from minari import __version__ as minari_version

        returns = [float(e.rewards.sum()) for e in episodes]
        storage.update_metadata(
            {
                "dataset_id": f"refpo/{refpo.get('task', 'task')}/{path.name}-v0",
                "minari_version": minari_version,
                "algorithm_name": str(refpo.get("policy", {}).get("algo", "unknown")),
                "author": {"refpo collect"},
                "ref_min_score": min(returns),
                "ref_max_score": max(returns),
                REFPO_KEY: refpo,
            }
        )
        if path.exists():  # overwrite: the old folder out of the way, the new one in, then the old one removed
            old = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.old.", suffix=".tmp"))
            os.replace(path, old / path.name)
            os.replace(tmp, path)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def _buffer(i: int, e: Episode):
    from minari.data_collector.episode_buffer import EpisodeBuffer

    return EpisodeBuffer(
        id=i,
        observations=e.observations.astype(np.float32),
        actions=e.actions.astype(np.float32),
        rewards=e.rewards.astype(np.float32),
        terminations=e.terminations.astype(bool),
        truncations=e.truncations.astype(bool),
        infos={},
    )


def read_dataset(path: str | Path) -> Dataset:
    """Read and check a Minari dataset folder; ``DataFileError`` naming the file for every problem."""
    path = Path(path).absolute()
    if not path.exists():
        raise DataFileError(
            f"dataset={path}: no such dataset (a folder written by refpo collect, or any Minari "
            f"dataset's data folder, holding {METADATA_FILE} and main_data.hdf5)"
        )
    if not path.is_dir():
        raise DataFileError(
            f"dataset={path}: not a Minari dataset (a folder holding {METADATA_FILE} and "
            f"main_data.hdf5, e.g. one written by refpo collect); found a file"
        )
    meta_path = path / METADATA_FILE
    if not meta_path.is_file():
        raise DataFileError(f"{path}: not a Minari dataset: no {METADATA_FILE} in it")
    try:
        metadata = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise DataFileError(f"{meta_path}: not readable as JSON ({type(err).__name__}: {err})") from None
    if not isinstance(metadata, dict):
        raise DataFileError(f"{meta_path}: not a Minari metadata file (it holds a {type(metadata).__name__})")
    data_format = metadata.get("data_format")
    if data_format != DATA_FORMAT:
        raise DataFileError(
            f"{meta_path}: unknown or unsupported data_format {data_format!r}; refpo_warp reads "
            f"Minari's '{DATA_FORMAT}' datasets"
        )
    missing = [k for k in ("observation_space", "action_space") if not isinstance(metadata.get(k), str)]
    if missing:  # Minari would gym.make() the env the file names to find them: that runs code; refuse instead
        raise DataFileError(
            f"{meta_path}: names no {' and no '.join(missing)}; refpo_warp needs both spaces in the "
            f"file (it does not build the environment a dataset names)"
        )
    storage_class = _minari()
    try:
        storage = storage_class.read(path)
        obs_space, action_space = storage.observation_space, storage.action_space
        total = storage.total_episodes
        episodes = [_episode(path, raw) for raw in storage.get_episodes(range(total))] if total else []
    except DataFileError:
        raise
    except Exception as err:  # (h5py and Minari raise many types for a damaged file; one message)
        raise DataFileError(
            f"{path}: cannot be read as a Minari dataset ({type(err).__name__}: {' '.join(str(err).split())[:300]})"
        ) from None
    obs_dim, action_dim = _box_dim(path, "observation_space", obs_space), _box_dim(path, "action_space", action_space)
    if not episodes:
        raise DataFileError(f"{path}: the dataset holds no episode")
    for i, e in enumerate(episodes):
        _check_episode(path, i, e, obs_dim, action_dim)
    low, high = (
        np.broadcast_to(np.asarray(b, np.float64), (action_dim,)) for b in (action_space.low, action_space.high)
    )
    return Dataset(path, episodes, obs_dim, action_dim, metadata, low, high)


def _box_dim(path: Path, name: str, space) -> int:
    shape = getattr(space, "shape", None)
    if type(space).__name__ != "Box" or shape is None or len(shape) != 1:
        raise DataFileError(f"{path}: its {name} is {space}; refpo_warp's tasks take flat Box spaces (one vector)")
    return int(shape[0])


def _episode(path: Path, raw: dict) -> Episode:
    def array(key: str) -> np.ndarray:
        value = raw.get(key)
        if not isinstance(value, np.ndarray):
            raise DataFileError(f"{path}: episode {raw.get('id')}: '{key}' is {type(value).__name__}, not one array")
        return value

    return Episode(
        array("observations"), array("actions"), array("rewards"), array("terminations"), array("truncations")
    )


ARRAYS = ("observations", "actions", "rewards", "terminations", "truncations")
NUMBER_KINDS = "biuf"  # numpy's kinds of bool, signed and unsigned integer, float: what an array may hold


def _check_episode(path: Path, i: int, e: Episode, obs_dim: int, action_dim: int) -> None:
    where = f"{path}: episode {i}"
    for key in ARRAYS:  # before any arithmetic: bytes, text or objects would fail in it
        dtype = getattr(e, key).dtype
        if dtype.kind not in NUMBER_KINDS:
            raise DataFileError(
                f"{where}: '{key}' holds {dtype} values ({_kind_name(dtype)}); a dataset's arrays hold numbers "
                f"(bool, integer or float)"
            )
    if e.rewards.ndim != 1:
        raise DataFileError(f"{where}: 'rewards' has shape {e.rewards.shape}, expected one value per step")
    t = e.length
    if t == 0:
        raise DataFileError(f"{where} has no step")
    expected = {"observations": (t + 1, obs_dim), "actions": (t, action_dim), "terminations": (t,), "truncations": (t,)}
    for key, shape in expected.items():
        if getattr(e, key).shape != shape:
            raise DataFileError(
                f"{where}: '{key}' has shape {getattr(e, key).shape}, expected {shape} "
                f"({t} steps, observation dim {obs_dim}, action dim {action_dim})"
            )
    for key in ("observations", "actions", "rewards"):
        values = np.asarray(getattr(e, key), dtype=np.float64)
        if not np.isfinite(values).all():
            bad = int((~np.isfinite(values)).sum())
            raise DataFileError(f"{where}: '{key}' holds {bad} NaN or infinite value(s)")
    ends = np.asarray(e.terminations, bool) | np.asarray(e.truncations, bool)
    if not ends[-1]:
        raise DataFileError(
            f"{where} is truncated mid-episode: its last step ({t}) is neither a termination nor a "
            f"truncation (a partly written or cut dataset)"
        )
    if ends[:-1].any():
        raise DataFileError(
            f"{where}: ends at step {int(np.argmax(ends)) + 1} of {t} and goes on (two episodes in one)"
        )


def _kind_name(dtype: np.dtype) -> str:
    names = {"S": "bytes", "U": "text", "O": "Python objects", "c": "complex numbers", "M": "dates", "m": "time spans"}
    return names.get(dtype.kind, "not numbers")


def env_differences(dataset: Dataset, task: str, env_options: dict) -> list[str]:
    """The env options where the env the dataset was recorded on (its ``refpo.env`` over the task's defaults) differs
    from ``task``'s env with ``env_options``, as ``env.<key>: <dataset's> in the dataset, <env's> here``."""
    recorded = dataset.refpo.get("env") or {}
    try:
        theirs = make_env_cfg(task, **recorded)
    except (ConfigError, TypeError, ValueError) as err:
        raise DataFileError(f"{dataset.path}: its env options {recorded} are not task {task}'s ({err})") from err
    ours = make_env_cfg(task, **env_options)
    names = [f.name for f in fields(ours)]
    return [
        f"env.{name}: {getattr(theirs, name)!r} in the dataset, {getattr(ours, name)!r} here"
        for name in names
        if getattr(theirs, name) != getattr(ours, name)
    ]


def check_spaces(dataset: Dataset, task: str, obs_dim: int, action_dim: int) -> None:
    """Refuse a dataset whose spaces are not the task's (and one recorded on another task, when it says so)."""
    recorded = dataset.refpo.get("task")
    if recorded is not None and recorded != task:
        raise DataFileError(f"{dataset.path}: recorded on task {recorded}; this run's task is {task}")
    if (dataset.obs_dim, dataset.action_dim) != (obs_dim, action_dim):
        raise DataFileError(
            f"{dataset.path}: its spaces (observation dim {dataset.obs_dim}, action dim "
            f"{dataset.action_dim}) are not task {task}'s (observation dim {obs_dim}, action dim "
            f"{action_dim})"
        )
