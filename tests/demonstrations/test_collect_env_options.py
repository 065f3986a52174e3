"""``refpo collect``'s env options (``env.<option>=``) on dmc_point_mass_wall, the real env on the CPU: a scripted
demonstrator's env and the demonstrator itself are built with them, the env a trained run's evaluation uses (its env
options, ``eval.env``'s over them) is the default and may be overridden, and the dataset's metadata records them. What
each dataset shows is checked against the options' numbers: the first observation of every episode (``start_spread``),
the rewards recomputed from the observations with an independent path length around the options' wall
(``wall_half_length``), and where the demonstrator passes the wall. A key the task does not have, or one that would
change a run's policy, exits 2 before anything is written."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("minari")

sys.path.insert(0, str(Path(__file__).parents[1] / "tasks" / "dmc"))
from dmc_mujoco_reference import wall_path_length

from refpo_warp.cli.main import main
from refpo_warp.demonstrations.dataset_file import read_dataset

TASK = "dmc_point_mass_wall"
SCRIPTED = ["collect", f"task={TASK}", "demonstrator=scripted"]
RADIUS, THICKNESS, DEFAULT_LENGTH = 0.01, 0.02, 0.15  # the mass's radius, the wall's default half-sizes


def collect(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    return code, capsys.readouterr().err


def expected_rewards(episode, length: float, steps: np.ndarray) -> np.ndarray:
    """The rewards of ``steps`` from the observations after them and the actions: (near + progress) / 2 x control,
    progress from the visibility-graph path around the wall of half-length ``length`` grown by the mass's radius."""
    a, b = THICKNESS + RADIUS, length + RADIUS
    p = episode.observations[steps + 1, :2].astype(np.float64)
    u = np.tanh(episode.actions[steps].astype(np.float64))  # the env's tanh on the policy's actions
    d = np.linalg.norm(p - [0.2, 0.0], axis=-1)
    near = 0.1 ** ((np.maximum(d - 0.015, 0) / 0.015) ** 2)
    path = np.array([wall_path_length(q, (0.2, 0.0), a, b) for q in p])
    progress = np.clip(1 - np.maximum(path - 0.015, 0), 0, 1)
    control = ((4 + np.clip(1 - u**2, 0, None)) / 5).mean(axis=-1)
    return 0.5 * (near + progress) * control


def assert_wall(dataset, length: float) -> None:
    """Every episode's rewards are those of the wall of half-length ``length``, and not of the default wall; every
    20th step whose position the reference path is defined at (outside the grown wall's box: a mass rounding the
    wall's corner may sit in the box's corner, outside the rounded region it cannot enter)."""
    a, b = THICKNESS + RADIUS, length + RADIUS
    for episode in dataset.episodes:
        p = np.abs(episode.observations[1:, :2])
        steps = np.array([t for t in range(0, len(episode.rewards), 20) if p[t, 0] >= a or p[t, 1] >= b])
        assert len(steps) > 40
        got = episode.rewards[steps].astype(np.float64)
        np.testing.assert_allclose(got, expected_rewards(episode, length, steps), atol=2e-5)
        assert np.abs(got - expected_rewards(episode, DEFAULT_LENGTH, steps)).max() > 0.01  # the check sees the wall


def test_a_scripted_demonstrator_collects_on_the_env_of_the_options(tmp_path, capsys):
    out = tmp_path / "data"
    argv = ["env.wall_half_length=0.22", "env.start_spread=0", "episodes=2", "num_envs=2", f"out={out}"]
    code, err = collect(capsys, *SCRIPTED, *argv)
    assert code == 0, err
    data = read_dataset(out)
    assert data.refpo["env"] == {"wall_half_length": 0.22, "start_spread": 0.0}
    assert_wall(data, 0.22)
    b = 0.22 + RADIUS
    clearance = min(0.05, (0.29 - b) / 2)  # the demonstrator's gap middle is at |y| = b + clearance = 0.26
    for episode in data.episodes:
        obs = episode.observations
        np.testing.assert_array_equal(obs[0], np.float32([-0.2, 0, 0, 0]))  # start_spread 0: the start itself
        in_band = np.abs(obs[:, 0]) <= THICKNESS  # beside the wall: the centre beyond its end plus the radius
        assert in_band.any() and (np.abs(obs[in_band, 1]) >= b - 1e-4).all()
        # it aimed at this wall's gap (switching to the next waypoint at b + c / 2), not the default's (|y| 0.21)
        assert b + clearance / 2 < np.abs(obs[:, 1]).max() <= b + clearance
        assert np.linalg.norm(obs[-1, :2] - [0.2, 0.0]) < 0.015


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ("env.wall_half_lenght=0.2", ("Unknown env option for task 'dmc_point_mass_wall' 'env.wall_half_lenght'. "
                                      "Did you mean 'env.wall_half_length'? Valid choices: env.action_chunk, ")),
        ("env.size=5", "option for task 'dmc_point_mass_wall' 'env.size': an env option of gridworld only"),
        ("env.wall_half_length=0.28", "env.wall_half_length=0.28 is invalid: the wall would close the arena"),
        ("env.action_chunk=2", "a scripted demonstrator acts one env step at a time"),
        ("env.task=point_mass", "env.task=point_mass: task=dmc_point_mass_wall sets env.task=point_mass_wall"),
    ],
)  # fmt: skip
def test_a_bad_env_option_exits_2_naming_it(option, message, tmp_path, capsys):
    code, err = collect(capsys, *SCRIPTED, option, "episodes=1", f"out={tmp_path / 'data'}")
    assert code == 2 and message in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []  # nothing written, not even a temp folder


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A one-iteration PPO run of the task with env options of its own, its evaluation's wall shorter (seconds)."""
    from refpo_warp.training import train

    run = tmp_path_factory.mktemp("run") / "run"
    train(
        [
            f"task={TASK}", "algo=ppo", "device=cpu", "seed=1", "num_envs=4", "runner.num_steps_per_env=8",
            "max_iterations=1", "eval.at_end=false", "env.start_spread=0", "env.wall_half_length=0.25",
            "eval.env.wall_half_length=0.2", f"run_dir={run}",
        ]
    )  # fmt: skip
    return run


def test_a_run_collects_on_the_env_its_evaluation_uses(run_dir, tmp_path, capsys):
    out = tmp_path / "data"
    code, err = collect(capsys, "collect", f"run_dir={run_dir}", "episodes=2", "num_envs=2", f"out={out}")
    assert code == 0, err
    data = read_dataset(out)
    assert data.refpo["env"] == {"start_spread": 0.0, "wall_half_length": 0.2}
    assert_wall(data, 0.2)
    for episode in data.episodes:
        np.testing.assert_array_equal(episode.observations[0], np.float32([-0.2, 0, 0, 0]))


def test_env_options_apply_over_the_runs(run_dir, tmp_path, capsys):
    out = tmp_path / "data"
    argv = ["env.start_spread=0.03", "env.wall_half_length=0.1", "episodes=4", "num_envs=4", f"out={out}"]
    code, err = collect(capsys, "collect", f"run_dir={run_dir}", *argv)
    assert code == 0, err
    data = read_dataset(out)
    assert data.refpo["env"] == {"start_spread": 0.03, "wall_half_length": 0.1}
    assert_wall(data, 0.1)
    starts = np.stack([e.observations[0] for e in data.episodes])
    assert (np.abs(starts[:, :2] - [-0.2, 0.0]) <= 0.03 + 1e-6).all() and (starts[:, 2:] == 0).all()
    assert math.dist(starts[0, :2], starts[1, :2]) > 0 and (starts[:, 0] != np.float32(-0.2)).all()  # spread


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ("env.wall_half_lenght=0.2", "Unknown env option for task 'dmc_point_mass_wall' 'env.wall_half_lenght'"),
        ("env.action_chunk=2", "env.action_chunk: 1 -> 2"),  # the policy's action size
    ],
)
def test_a_bad_env_option_for_a_run_exits_2_naming_it(option, message, run_dir, tmp_path, capsys):
    code, err = collect(capsys, "collect", f"run_dir={run_dir}", option, "episodes=1", f"out={tmp_path / 'data'}")
    assert code == 2 and message in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []
