"""A committed result cannot drift silently (issue 48): every committed run under docs/results/ (a folder with a
config.yaml) is made by one command of ``docs/results/provenance.yaml``, and that command, resolved on today's code,
gives the run's config, or the registry records the commit the run was made at and exactly how it differs. A profile
that moves under a committed result fails here until its page is rerun or pins the old values
(``refpo_warp/studies/reports/provenance.py``)."""

from __future__ import annotations

import copy
import functools
from dataclasses import replace

import pytest
import yaml

from refpo_warp.config.resolve import resolve_config
from refpo_warp.studies.reports import provenance
from refpo_warp.studies.reports.provenance import ABSENT, RESULTS, Entry, check, config_difference

ENTRIES = provenance.read_registry()
IDS = [f"{i:02d}:{e.folder}" for i, e in enumerate(ENTRIES)]


@functools.cache
def checked(i: int) -> provenance.Checked:
    return check(ENTRIES[i])


def test_every_committed_run_is_made_by_exactly_one_entry():
    loose, twice = provenance.unclaimed([checked(i) for i in range(len(ENTRIES))])
    assert not loose, f"committed runs no entry of {provenance.REGISTRY.name} makes (add the command): {loose}"
    assert not twice, f"committed runs two entries make (one command per run): {twice}"


@pytest.mark.parametrize("i", range(len(ENTRIES)), ids=IDS)
def test_the_runs_are_what_the_command_makes_today_or_the_registry_says_how_not(i):
    entry = ENTRIES[i]
    assert entry.page is None or (RESULTS / entry.page).exists(), f"{entry.folder}: no page {entry.page}"
    problems = checked(i).problems()
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("i", [i for i, e in enumerate(ENTRIES) if e.made_at], ids=lambda i: IDS[i])
def test_made_at_is_the_commit_that_added_the_runs(i):
    found = provenance.adding_commits(checked(i))
    if found is None:
        pytest.skip("no git history here (git missing or a shallow clone)")
    assert provenance.same_commits(ENTRIES[i].made_at, found), (
        f"{ENTRIES[i].folder}: made_at {list(ENTRIES[i].made_at)}; git log finds its runs added at {found}"
    )


# ------------------------------------------------------------------------------------------------ the comparison
def gridworld(*args: str) -> dict:
    return resolve_config(["task=gridworld", "algo=ppo", "device=cpu", *args], device_type="cpu")


def test_the_difference_is_each_key_saved_and_today_with_absent_keys_named():
    today = gridworld()
    saved = copy.deepcopy({**today, "run_dir": "elsewhere", "device": "cuda"})  # neither changes what a run computes
    saved["algorithm"]["learning_rate"] = 0.01
    del saved["eval"]["at_end"]
    assert config_difference(saved, today) == {
        "algorithm.learning_rate": [0.01, today["algorithm"]["learning_rate"]],
        "eval.at_end": [ABSENT, True],
    }
    assert config_difference(today, {**today, "seed": 7}) == {"seed": [today["seed"], 7]}


def test_options_that_act_only_in_another_command_or_with_a_checkpoint_are_left_out():
    today = gridworld()
    old = {k: v for k, v in today.items() if k not in ("init_from", "pretrain", "clone_normalizer")}
    assert config_difference(old, today) == {}  # a run from before refpo pretrain computes the same
    tuned = gridworld("init_from=runs/clone")
    old = {k: v for k, v in tuned.items() if k != "clone_normalizer"}
    assert config_difference(old, tuned) == {"clone_normalizer": [ABSENT, tuned["clone_normalizer"]]}
    clone = gridworld("pretrain.dataset=runs/data")
    assert config_difference({**clone, "pretrain": {**clone["pretrain"], "epochs": 3}}, clone) == {
        "pretrain.epochs": [3, clone["pretrain"]["epochs"]]
    }


def test_a_moved_value_fails_until_the_registry_records_it(tmp_path):
    command = "refpo train task=gridworld algo=ppo total_env_steps=4096"
    saved = gridworld("total_env_steps=4096", "algorithm.learning_rate=0.01")
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(saved), encoding="utf-8")
    entry = Entry(str(tmp_path), command)  # an absolute folder stands for itself
    problems = check(entry).problems()
    assert len(problems) == 2 and "algorithm.learning_rate" in problems[0] and "made_at" in problems[1]
    difference = {"algorithm.learning_rate": [0.01, gridworld()["algorithm"]["learning_rate"]]}
    assert check(replace(entry, made_at=("abcdef0",), difference=difference)).problems() == []
    wrong = {"algorithm.learning_rate": [0.02, difference["algorithm.learning_rate"][1]]}
    assert "records" in check(replace(entry, made_at=("abcdef0",), difference=wrong)).problems()[0]
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(gridworld("total_env_steps=4096")), encoding="utf-8")
    assert "drop made_at" in check(replace(entry, made_at=("abcdef0",))).problems()[0]


def test_an_entry_whose_runs_differ_in_different_ways_must_be_split(tmp_path):
    for seed, rate in ((1, 0.01), (2, 0.02)):
        run = tmp_path / "gridworld" / "ppo" / f"seed{seed}"
        run.mkdir(parents=True)
        saved = gridworld(f"seed={seed}", f"algorithm.learning_rate={rate}")
        (run / "config.yaml").write_text(yaml.safe_dump(saved), encoding="utf-8")
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text("device: cpu\ntasks: [gridworld]\nseeds: [1, 2]\nmethods: [ppo]\n", encoding="utf-8")
    found = check(Entry(str(tmp_path), f"refpo sweep {sweep}"))
    assert sorted(found.committed) == ["gridworld/ppo/seed1", "gridworld/ppo/seed2"]
    assert "split the entry" in found.problems()[0]


def test_a_commit_hash_yaml_reads_as_a_number_is_refused(tmp_path):
    path = tmp_path / "provenance.yaml"
    path.write_text("entries:\n- {folder: x, command: refpo train, made_at: 4e63504}\n", encoding="utf-8")
    with pytest.raises(provenance.ConfigError, match="quoted"):
        provenance.read_registry(path)
