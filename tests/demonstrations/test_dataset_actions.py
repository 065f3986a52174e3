"""What a dataset's actions are (``pretrain.dataset_actions``): the atanh conversion of env-unit actions on a tanh task
against hand-worked values, what ``auto`` decides from the file, and the clone trained on the converted actions
through ``refpo pretrain``, its choice in config.yaml; every unsure or impossible case refused naming the option."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("minari")

sys.path.insert(0, str(Path(__file__).parents[1] / "training"))
from dataset_helpers import episode, minari_dataset, rewrite_episode, with_actions, write
from reliability_helpers import TINY, assert_refused, call_tool

from refpo_warp.demonstrations.dataset_actions import action_units
from refpo_warp.demonstrations.dataset_file import read_dataset
from refpo_warp.utils.errors import DataFileError

BAD_FILE = 4
MARGIN = 1e-6
# atanh(x) = ln((1 + x) / (1 - x)) / 2 by hand: atanh(0.5) = ln 3 / 2; atanh(0.9) = ln 19 / 2; atanh(0.999) =
# ln 1999 / 2; at the bound 1 - 1e-6: ln(1.999999 / 0.000001) / 2 = (ln 2e6 + ln(1 - 5e-7)) / 2
# = (0.6931471806 + 6 x 2.3025850930 - 5e-7) / 2 = 7.2543286195
AT_BOUND = 7.2543286195
RTOL = 1e-5  # the dataset's float32 0.999 is 0.99900001: atanh's slope there, 1 / (1 - 0.999^2) = 500, moves it 2e-6
ATANH = {0.5: 0.5493061443, 0.9: 1.4722194895, 0.999: 3.8002011672, 0.25: 0.2554128119, 0.1: 0.1003353477}
# two episodes on dmc_point_mass's spaces (observation dim 4, action dim 2), actions in env units: 1.0 and -1.0 at
# the bound, 1.0000005 (float32: 1.00000048) rounding just past it: the three clipped values
ENV_ACTIONS = [
    [[0.5, -0.9], [1.0, -1.0], [0.0, 0.25]],
    [[0.999, -0.1], [1.0000005, 0.1]],
]
CLONED = [
    [[ATANH[0.5], -ATANH[0.9]], [AT_BOUND, -AT_BOUND], [0.0, ATANH[0.25]]],
    [[ATANH[0.999], -ATANH[0.1]], [AT_BOUND, ATANH[0.1]]],
]


def env_unit_episodes():
    return [
        with_actions(episode(3, obs_dim=4, seed=1), ENV_ACTIONS[0]),
        with_actions(episode(2, obs_dim=4, seed=2), ENV_ACTIONS[1]),
    ]


def test_env_units_on_a_tanh_task_are_atanh_of_the_clipped_actions(datasets):
    data = read_dataset(datasets["bounded"])
    units = action_units(data, "env_units", True, MARGIN, "gridworld")
    assert (units.units, units.atanh, units.bound, units.clipped) == ("env_units", True, 1 - MARGIN, 3)
    for e, want in zip(data.episodes, CLONED):
        np.testing.assert_allclose(units.apply(e.actions), want, rtol=RTOL, atol=1e-7)
    assert units.apply(data.episodes[0].actions).dtype == np.float32
    assert units.summary() == {"dataset_actions": "env_units", "actions_atanh": True, "actions_clipped": 3}
    # a wider margin: the bound 0.99, atanh(0.99) = ln 199 / 2 = 2.6466524124, and 0.999 clipped to it too
    wide = action_units(data, "env_units", True, 0.01, "gridworld")
    assert wide.clipped == 4
    np.testing.assert_allclose(wide.apply(data.episodes[1].actions)[:, 0], [2.6466524124] * 2, rtol=1e-6)


@pytest.fixture(scope="module")
def datasets(tmp_path_factory):
    """The same two episodes as refpo collect writes them, and as Minari writes them with a bounded and an unbounded
    action space."""
    root = tmp_path_factory.mktemp("datasets")
    return {
        "refpo collect": write(root / "ours", env_unit_episodes()),
        "bounded": minari_dataset(root / "bounded", env_unit_episodes()),
        "unbounded": minari_dataset(root / "unbounded", env_unit_episodes(), -np.inf, np.inf),
        "half-bounded": minari_dataset(root / "half", env_unit_episodes(), -np.inf, 1.0),
    }


@pytest.mark.parametrize(
    "source,squash,decided",
    [
        ("refpo collect", False, "pre_squash"),  # the policy's own actions, whatever its space says
        ("unbounded", True, "pre_squash"),  # no tanh output is unbounded
        ("unbounded", False, "pre_squash"),
        ("bounded", False, "env_units"),  # the env's actions are the policy's: taken as they are
        ("half-bounded", False, "env_units"),
    ],
)
def test_auto_decides_from_the_file(datasets, source, squash, decided):
    units = action_units(read_dataset(datasets[source]), "auto", squash, MARGIN, "gridworld")
    assert (units.units, units.atanh) == (decided, False)


@pytest.mark.parametrize("source", ["bounded", "half-bounded"])
def test_auto_refuses_a_bounded_space_on_a_tanh_task_naming_the_option(datasets, source):
    data = read_dataset(datasets[source])
    with pytest.raises(DataFileError) as err:
        action_units(data, "auto", True, MARGIN, "dmc_point_mass")
    message = str(err.value)
    space = "Box(-1, 1)" if source == "bounded" else "Box(-inf, 1)"
    assert message.startswith(
        f"{data.path}: its actions lie in a bounded space, {space} (largest magnitude 1), and task dmc_point_mass's "
    )
    assert "pretrain.dataset_actions=env_units" in message and "pretrain.dataset_actions=pre_squash" in message


def test_a_given_setting_is_followed_and_pre_squash_is_taken_as_it_is(datasets):
    data = read_dataset(datasets["bounded"])
    units = action_units(data, "pre_squash", True, MARGIN, "gridworld")
    assert (units.units, units.atanh, units.clipped) == ("pre_squash", False, 0)
    assert units.apply(data.episodes[0].actions) is data.episodes[0].actions
    ours = action_units(read_dataset(datasets["refpo collect"]), "env_units", True, MARGIN, "gridworld")
    assert ours.atanh and ours.clipped == 3


def test_refpo_collect_records_its_units_and_auto_reads_them(tmp_path):
    path = write(tmp_path / "data", env_unit_episodes())
    meta = json.loads((path / "metadata.json").read_text())
    meta["refpo"].update(action_units="pre_squash", action_transform="tanh")
    (path / "metadata.json").write_text(json.dumps(meta))
    assert action_units(read_dataset(path), "auto", True, MARGIN, "dmc_point_mass").units == "pre_squash"
    # collected where the env clipped, cloned where it squashes: its actions are not this policy's
    meta["refpo"]["action_transform"] = "clip"
    (path / "metadata.json").write_text(json.dumps(meta))
    with pytest.raises(DataFileError, match=r"collected with env\.action_transform=clip.*pretrain\.dataset_actions="):
        action_units(read_dataset(path), "auto", True, MARGIN, "dmc_point_mass")
    meta["refpo"].update(action_units="radians", action_transform="tanh")
    (path / "metadata.json").write_text(json.dumps(meta))
    with pytest.raises(DataFileError, match="records action_units='radians'; expected 'pre_squash' or 'env_units'"):
        action_units(read_dataset(path), "auto", True, MARGIN, "dmc_point_mass")


def test_env_units_beyond_the_bound_are_refused_naming_the_episode(tmp_path):
    path = minari_dataset(tmp_path / "data", env_unit_episodes())
    rewrite_episode(path, "actions", lambda a: a * 1.5)  # episode 0: 0.75, -1.35, 1.5, ...
    data = read_dataset(path)
    with pytest.raises(DataFileError) as err:
        action_units(data, "env_units", True, MARGIN, "dmc_point_mass")
    assert str(err.value).startswith(f"{path}: episode 0: an action of magnitude 1.5 is no action of task ")
    assert "pretrain.dataset_actions=pre_squash" in str(err.value)
    assert not action_units(data, "env_units", False, MARGIN, "gridworld").atanh  # no squash: taken as they are


# ------------------------------------------------------------------------------------------------ refpo pretrain
# dmc_point_mass squashes with tanh (the DMC tasks' default env.action_transform); a clone of one epoch, evaluated
# for 20 steps
DMC = ["task=dmc_point_mass", "algo=refpo", "device=cpu", "num_envs=4", "actor.hidden_dims=[16]"]
DMC += ["critic.hidden_dims=[16]", "eval.num_envs=2", "eval.flow_steps=[1]", "eval.max_steps=20", "pretrain.epochs=1"]
TANH_GRIDWORLD = [*TINY, "env.action_transform=tanh", "pretrain.epochs=1", "algo=refpo"]


@pytest.fixture
def trained_on(monkeypatch):
    """The (training, validation) pairs ``refpo pretrain`` hands to the cloning, captured."""
    from refpo_warp.demonstrations import pretrain_run

    seen = {}
    real = pretrain_run.clone

    def clone(actor, loss, groups, train, validation, *rest):
        seen["train"], seen["validation"] = train, validation
        return real(actor, loss, groups, train, validation, *rest)

    monkeypatch.setattr(pretrain_run, "clone", clone)
    return seen


def rows(pairs) -> list[list[float]]:
    return sorted(np.concatenate([pairs["train"][1], pairs["validation"][1]]).tolist())


def test_pretrain_clones_env_unit_actions_through_atanh_and_records_it(datasets, tmp_path, trained_on):
    run = tmp_path / "clone"
    proc = call_tool(
        "pretrain", *DMC, f"dataset={datasets['bounded']}", "pretrain.dataset_actions=env_units", f"run_dir={run}"
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    np.testing.assert_allclose(rows(trained_on), sorted(r for e in CLONED for r in e), rtol=RTOL, atol=1e-7)
    assert "pretrain.dataset_actions=env_units: atanh(clip(a, ±0.999999)), 3 value(s) clipped" in proc.stdout
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["pretrain"]["dataset_actions"] == "env_units" and cfg["pretrain"]["squash_margin"] == MARGIN
    summary = json.loads((run / "eval.json").read_text())["pretrain"]
    assert (summary["dataset_actions"], summary["actions_atanh"], summary["actions_clipped"]) == ("env_units", True, 3)


def test_pretrain_refuses_a_bounded_foreign_dataset_on_a_tanh_task_naming_the_option(datasets, tmp_path):
    run = tmp_path / "clone"
    proc = call_tool("pretrain", *DMC, f"dataset={datasets['bounded']}", f"run_dir={run}")
    assert_refused(
        proc, BAD_FILE, "bounded", "pretrain.dataset_actions=env_units", "pretrain.dataset_actions=pre_squash"
    )
    assert not run.exists()


def test_pretrain_takes_an_unbounded_dataset_as_it_is_and_records_auto_s_choice(datasets, tmp_path, trained_on):
    run = tmp_path / "clone"
    proc = call_tool("pretrain", *DMC, f"dataset={datasets['unbounded']}", f"run_dir={run}")
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    np.testing.assert_array_equal(rows(trained_on), sorted(np.float32(r).tolist() for e in ENV_ACTIONS for r in e))
    assert yaml.safe_load((run / "config.yaml").read_text())["pretrain"]["dataset_actions"] == "pre_squash"
    assert "pretrain.dataset_actions=pre_squash: taken as they are" in proc.stdout


def test_a_bad_dataset_actions_value_is_refused_naming_the_choices(datasets, tmp_path):
    proc = call_tool("pretrain", *DMC, f"dataset={datasets['unbounded']}", "pretrain.dataset_actions=post_tanh")
    assert_refused(proc, 2, "pretrain.dataset_actions", "auto", "pre_squash", "env_units")
    proc = call_tool("pretrain", *DMC, f"dataset={datasets['unbounded']}", "pretrain.squash_margin=0")
    assert_refused(proc, 2, "pretrain.squash_margin")


def test_pretrain_refuses_a_non_numeric_array_with_exit_4(tmp_path):
    path = write(tmp_path / "data")
    rewrite_episode(path, "actions", lambda a: np.full(a.shape, b"0.5"))
    run = tmp_path / "clone"
    proc = call_tool("pretrain", *TANH_GRIDWORLD, f"dataset={path}", f"run_dir={run}")
    assert_refused(proc, BAD_FILE, f"{path}: episode 0: 'actions' holds |S3 values (bytes)")
    assert not run.exists()
