"""The demonstrations workflow through the refpo command, as a user runs it: collect, pretrain, train init_from=.

Checks: the dataset and the pretrain run's files; rsl_rl's own ``OnPolicyRunner.load`` reads the clone; a fine-tuning
run starts from exactly the cloned weights and keeps them through the critic's warm-up while the critic learns; and
every bad dataset or mismatched clone is refused with exit 4, one message naming it, and no run dir.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
import torch

pytest.importorskip("minari")

sys.path.insert(0, str(Path(__file__).parents[1] / "training"))
from dataset_helpers import damage, episode, write
from reliability_helpers import TINY as TINY_RUN
from reliability_helpers import assert_refused, call_tool, tree_hash

USAGE, BAD_FILE = 2, 4
# The reliability tests' tiny GridWorld run, evaluated at two flow step counts and with the default checkpoints.
TINY = [o for o in TINY_RUN if not o.startswith(("eval.flow_steps=", "runner.save_interval="))]
TINY += ["eval.flow_steps=[1, 2]", "actor.obs_normalization=true", "critic.obs_normalization=true"]
PRETRAIN = [*TINY, "pretrain.epochs=3", "pretrain.batch_size=64"]


@pytest.fixture(scope="module")
def workflow(tmp_path_factory):
    """A scripted-demonstrator dataset and a flow clone of it (seconds)."""
    root = tmp_path_factory.mktemp("workflow")
    proc = call_tool(
        "collect", "task=gridworld", "demonstrator=scripted", "episodes=40", "num_envs=8", f"out={root / 'data'}"
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    proc = call_tool("pretrain", *PRETRAIN, "algo=refpo", f"dataset={root / 'data'}", f"run_dir={root / 'clone'}")
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    assert "note:" not in proc.stdout  # the dataset's env is the clone's
    return root


def test_collect_writes_the_episodes_and_who_made_them(workflow):
    from refpo_warp.demonstrations.dataset_file import read_dataset

    data = read_dataset(workflow / "data")
    assert len(data.episodes) == 40 and (data.obs_dim, data.action_dim) == (2, 2)
    assert data.refpo["task"] == "gridworld" and data.refpo["policy"]["kind"] == "gridworld's scripted demonstrator"
    assert data.refpo["policy"]["up_share"] == 0.7 and data.refpo["obs_groups"] == ["policy"]
    # the policy's own actions, on an env that clips them (pretrain.dataset_actions=auto reads both)
    assert (data.refpo["action_units"], data.refpo["action_transform"]) == ("pre_squash", "clip")
    # GridWorld's episodes end at a goal row (terminated) or at the 200-step time-out (truncated)
    assert all(bool(e.terminations[-1] or e.truncations[-1]) for e in data.episodes)
    assert all(abs(e.observations[-1, 1]) >= 21 / 24 - 1e-6 for e in data.episodes if e.terminations[-1])


def test_collect_never_overwrites_unless_asked(workflow, tmp_path):
    out = tmp_path / "data"
    assert call_tool("collect", "task=gridworld", "demonstrator=scripted", "episodes=4", f"out={out}").returncode == 0
    before = tree_hash(out)
    proc = call_tool("collect", "task=gridworld", "demonstrator=scripted", "episodes=6", f"out={out}")
    assert_refused(proc, USAGE, f"out={out} exists", "overwrite=true")
    assert tree_hash(out) == before
    proc = call_tool("collect", "task=gridworld", "demonstrator=scripted", "episodes=6", f"out={out}", "overwrite=true")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert json.loads((out / "metadata.json").read_text())["total_episodes"] == 6


def test_collect_from_a_trained_run_with_noise(workflow, tmp_path):
    out = tmp_path / "from_clone"
    proc = call_tool("collect", f"run_dir={workflow / 'clone'}", "episodes=8", "noise=0.2", f"out={out}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    meta = json.loads((out / "metadata.json").read_text())["refpo"]
    assert meta["policy"]["algo"] == "refpo" and meta["policy"]["action_noise_std"] == 0.2
    assert meta["policy"]["checkpoint"].endswith("model_0.pt")


def test_pretrain_writes_a_run_that_rsl_rl_loads(workflow):
    from rsl_rl.runners import OnPolicyRunner

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import rsl_rl_config

    clone = workflow / "clone"
    rows = [json.loads(line) for line in (clone / "progress.jsonl").read_text().splitlines()]
    assert [r["epoch"] for r in rows] == [0, 1, 2] and all(r["val_loss"] > 0 for r in rows)
    results = json.loads((clone / "eval.json").read_text())
    assert set(results["results"]) == {"N=1", "N=2"} and results["dataset"]["episodes"] == 40
    assert list(clone.glob("events.out.tfevents.*"))
    cfg = load_run(clone, {}).cfg
    assert cfg["pretrain"]["dataset_actions"] == "pre_squash"  # auto's choice for refpo collect's data, recorded
    assert results["pretrain"]["dataset_actions"] == "pre_squash" and not results["pretrain"]["actions_atanh"]
    env = make_env("gridworld", num_envs=4, device="cpu")
    runner = OnPolicyRunner(env, rsl_rl_config(cfg), log_dir=None, device="cpu")
    runner.load(str(clone / "model_0.pt"))  # rsl_rl's own loader
    saved = torch.load(clone / "model_0.pt", weights_only=True)["actor_state_dict"]
    for name, tensor in runner.alg.actor.state_dict().items():
        assert torch.equal(tensor, saved[name]), name


def test_pretrain_names_the_env_options_where_the_dataset_differs(workflow, tmp_path):
    run = tmp_path / "clone"
    proc = call_tool(
        "pretrain",
        *PRETRAIN,
        "algo=refpo",
        f"dataset={workflow / 'data'}",
        "env.max_episode_length=77",
        f"run_dir={run}",
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    from refpo_warp.envs.registry import make_env_cfg

    default = make_env_cfg("gridworld").max_episode_length  # the dataset's: collected at the task's defaults
    note = "note: the dataset's env is not the one the clone is evaluated on: env.max_episode_length:"
    assert f"{note} {default} in the dataset, 77 here" in proc.stdout


def fine_tune(workflow, run, *options):
    """A tiny ReFPO run from the workflow's clone into ``run`` (no final evaluation); its finished process."""
    proc = call_tool(
        "train", *TINY, "algo=refpo", f"init_from={workflow / 'clone'}", "eval.at_end=false", f"run_dir={run}", *options
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


def test_fine_tuning_starts_from_the_clone_and_keeps_it_through_the_warmup(workflow, tmp_path):
    clone = torch.load(workflow / "clone" / "model_0.pt", weights_only=True)
    run = tmp_path / "tuned"
    proc = fine_tune(workflow, run, "max_iterations=2", "critic_warmup_iterations=1", "runner.save_interval=1")
    assert "starting from the cloned actor" in proc.stdout and "iterations 0..0 train the critic alone" in proc.stdout
    warm, moved = (torch.load(run / f"model_{i}.pt", weights_only=True) for i in (0, 1))
    for name, tensor in clone["actor_state_dict"].items():
        assert torch.equal(warm["actor_state_dict"][name], tensor), name  # iteration 0: the warm-up
    assert any(not torch.equal(moved["actor_state_dict"][k], v) for k, v in clone["actor_state_dict"].items())
    assert any(not torch.equal(warm["critic_state_dict"][k], v) for k, v in clone["critic_state_dict"].items())
    rows = [json.loads(line) for line in (run / "progress.jsonl").read_text().splitlines()]
    assert rows[0]["Flow/clip_fraction"] == 0.0
    # clone_normalizer=keep (the default): both normalisers hold the data's statistics after the warm-up too
    assert "keep the data's statistics" in proc.stdout
    for model in ("actor_state_dict", "critic_state_dict"):
        kept = {k: v for k, v in clone[model].items() if "obs_normalizer" in k}
        assert kept and all(torch.equal(moved[model][k], v) for k, v in kept.items()), model


def test_fine_tuning_may_update_the_normalisers_from_the_rollouts(workflow, tmp_path):
    clone = torch.load(workflow / "clone" / "model_0.pt", weights_only=True)
    run = tmp_path / "tuned"
    fine_tune(workflow, run, "clone_normalizer=update", "max_iterations=1", "critic_warmup_iterations=0")
    moved = torch.load(run / "model_0.pt", weights_only=True)
    for model in ("actor_state_dict", "critic_state_dict"):
        counts = [k for k in clone[model] if k.endswith("obs_normalizer.count")]
        assert counts and all(moved[model][k] > clone[model][k] for k in counts), model


@pytest.mark.parametrize(
    "override,culprits",
    [
        ("actor.hidden_dims=[32]", ["actor.hidden_dims: [16] -> [32]"]),
        ("algo=ppo", ["actor.class_name: 'refpo_warp.models:FlowActor' -> 'rsl_rl.models:MLPModel'"]),
    ],
)
def test_a_clone_that_does_not_fit_is_refused_before_anything_is_written(workflow, tmp_path, override, culprits):
    dropped = {override.split("=")[0], *(["algorithm.num_mc_samples"] if override == "algo=ppo" else [])}
    args = [a for a in TINY if a.split("=")[0] not in dropped]
    algo = [] if override.startswith("algo=") else ["algo=refpo"]
    run = tmp_path / "tuned"
    proc = call_tool("train", *args, *algo, override, f"init_from={workflow / 'clone'}", f"run_dir={run}")
    assert_refused(proc, BAD_FILE, "init_from=", "does not fit", *culprits)
    assert not run.exists()


def test_init_from_a_folder_that_is_no_run(tmp_path):
    run = tmp_path / "tuned"
    proc = call_tool("train", *TINY, "algo=refpo", f"init_from={tmp_path / 'nothing'}", f"run_dir={run}")
    assert_refused(proc, BAD_FILE, f"init_from={tmp_path / 'nothing'}")
    assert not run.exists()


def point_mass_dataset(path):
    return write(path, [episode(5, obs_dim=4, action_dim=2, seed=1)], task="dmc_point_mass")


@pytest.mark.parametrize(
    "kind,culprit",
    [
        ("missing", "no such dataset"),
        ("empty", "holds no episode"),
        ("NaN", "NaN or infinite"),
        ("truncated mid-episode", "truncated mid-episode"),
        ("unknown format", "unsupported data_format"),
        ("other task", "recorded on task dmc_point_mass"),
        ("other spaces", "observation dim 4"),
    ],
)
def test_a_bad_dataset_is_refused_with_no_run_dir(tmp_path, kind, culprit):
    if kind == "other task":
        path = point_mass_dataset(tmp_path / "data")
    elif kind == "other spaces":
        path = write(tmp_path / "data", [episode(5, obs_dim=4, seed=1), episode(3, obs_dim=4, seed=2)], task=None)
    else:
        path = damage(kind, write(tmp_path / "data"))
    run = tmp_path / "clone"
    proc = call_tool("pretrain", *PRETRAIN, "algo=refpo", f"dataset={path}", f"run_dir={run}")
    assert_refused(proc, BAD_FILE, str(path.name), culprit)
    assert not run.exists()


def test_a_bad_pretrain_option_is_refused_before_the_dataset_is_read(tmp_path):
    run = tmp_path / "clone"
    proc = call_tool(
        "pretrain",
        *PRETRAIN,
        "algo=refpo",
        "pretrain.validation_fraction=1",
        f"dataset={tmp_path / 'nowhere'}",
        f"run_dir={run}",
    )
    assert_refused(proc, USAGE, "pretrain.validation_fraction=1")
    assert not run.exists()


def test_refpo_eval_reads_a_pretrain_run(workflow, tmp_path):
    """A pretrain run is a run: refpo eval evaluates its checkpoint again, to the same numbers."""
    import shutil

    clone = shutil.copytree(workflow / "clone", tmp_path / "clone")
    before = json.loads((clone / "eval.json").read_text())["results"]
    proc = call_tool("eval", f"run_dir={clone}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads((clone / "eval.json").read_text())["results"] == before


def test_a_resumed_fine_tuning_run_finishes_its_warmup(workflow, tmp_path):
    """Stopped inside the critic's warm-up, a resumed run keeps the actor frozen until the warm-up ends."""
    clone = torch.load(workflow / "clone" / "model_0.pt", weights_only=True)["actor_state_dict"]
    run = tmp_path / "tuned"
    common = [*TINY, "algo=refpo", "runner.save_interval=1", "eval.at_end=false"]
    proc = call_tool(
        "train",
        *common,
        f"init_from={workflow / 'clone'}",
        "critic_warmup_iterations=3",
        "max_iterations=2",
        f"run_dir={run}",
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    proc = call_tool("train", f"run_dir={run}", "resume=true", "max_iterations=4")
    assert proc.returncode == 0, proc.stderr[-3000:]
    actors = [torch.load(run / f"model_{i}.pt", weights_only=True)["actor_state_dict"] for i in range(4)]
    assert all(torch.equal(actors[2][k], v) for k, v in clone.items())  # iteration 2: still the warm-up
    assert any(not torch.equal(actors[3][k], v) for k, v in clone.items())
