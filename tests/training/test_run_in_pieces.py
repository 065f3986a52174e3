"""A run trained in pieces (``stop_after_iterations`` / ``stop_after_minutes``, then ``resume=true``) ends bit-identical
to the same run trained in one call: every tensor of the final checkpoint (the models with their normalisers, the
optimizer state, the env's state) is ``torch.equal`` to the unbroken run's, and so is every progress row but its
clock."""

import contextlib
import io

import pytest
import torch

from refpo_warp.runner.checkpoints import read_checkpoint
from refpo_warp.runner.progress import read_rows
from refpo_warp.training import train

ITERATIONS = 4


def options(algo: str) -> list[str]:
    # random first episode lengths and an evaluation every 2 iterations: both draw from the streams a resume restores
    return [
        "task=gridworld",
        f"algo={algo}",
        "device=cpu",
        "num_envs=4",
        "runner.num_steps_per_env=8",
        f"max_iterations={ITERATIONS}",
        "runner.init_at_random_ep_len=true",
        "runner.save_interval=100",
        "algorithm.num_mini_batches=2",
        "algorithm.num_learning_epochs=2",
        "eval.interval=2",
        "eval.interval_num_envs=2",
        "eval.at_end=false",
    ]


def quiet_train(args: list[str]) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        train(args)
    return out.getvalue()


def tensors(value, path=""):
    """Every tensor in a checkpoint, by its path (dicts and lists walked)."""
    if isinstance(value, torch.Tensor):
        yield path, value
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from tensors(item, f"{path}.{key}")
    elif isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            yield from tensors(item, f"{path}[{i}]")


def assert_bitwise_equal(whole_dir, pieces_dir) -> None:
    last = f"model_{ITERATIONS - 1}.pt"
    whole, pieces = read_checkpoint(whole_dir / last), read_checkpoint(pieces_dir / last)
    a, b = dict(tensors(whole)), dict(tensors(pieces))
    assert set(a) == set(b)
    assert any(k.startswith(".actor_state_dict") for k in a) and any(k.startswith(".run_state.env") for k in a)
    differ = [k for k in a if not torch.equal(a[k], b[k])]
    assert not differ, differ
    assert whole["iter"] == pieces["iter"] == ITERATIONS - 1
    assert whole["refpo_warp"]["env_steps"] == pieces["refpo_warp"]["env_steps"] == ITERATIONS * 4 * 8
    # the progress rows too (losses, episode means, periodic evaluations), but for the clock's
    clock = ("time_s", "steps_per_s")
    rows = [[{k: v for k, v in r.items() if k not in clock} for r in read_rows(d)] for d in (whole_dir, pieces_dir)]
    assert [r["iteration"] for r in rows[1]] == list(range(ITERATIONS))
    assert rows[0] == rows[1] and "reward_mean" in rows[0][-1] and any(k.startswith("eval/") for k in rows[0][-1])


@pytest.fixture(scope="module")
def unbroken(tmp_path_factory):
    """The run of each algo trained in one call."""
    root = tmp_path_factory.mktemp("unbroken")
    for algo in ("ppo", "refpo"):
        quiet_train([*options(algo), f"run_dir={root / algo}"])
    return root


@pytest.mark.slow(minutes=2)
@pytest.mark.parametrize("algo", ["ppo", "refpo"])
def test_a_run_cut_after_two_iterations_and_resumed_ends_bitwise_equal(unbroken, tmp_path, algo):
    run_dir = tmp_path / algo
    said = quiet_train([*options(algo), f"run_dir={run_dir}", "stop_after_iterations=2"])
    assert "stopped after iteration 1 of 0..3 (stop_after_iterations=2)" in said and "resume=true continues" in said
    assert sorted(p.name for p in run_dir.glob("model_*.pt")) == ["model_0.pt", "model_1.pt"]
    quiet_train([f"run_dir={run_dir}", "resume=true"])  # the saved stop_after_iterations=2: the last two
    assert_bitwise_equal(unbroken / algo, run_dir)


@pytest.mark.slow(minutes=2)
def test_a_run_advanced_by_a_time_limit_learns_an_iteration_a_call_and_ends_bitwise_equal(unbroken, tmp_path):
    """A limit shorter than any iteration: every call learns one iteration (the least) and stops at a checkpoint."""
    run_dir = tmp_path / "ppo"
    quiet_train([*options("ppo"), f"run_dir={run_dir}", "stop_after_minutes=0.0001"])
    for it in range(1, ITERATIONS):
        assert (run_dir / f"model_{it - 1}.pt").exists() and not (run_dir / f"model_{it}.pt").exists()
        quiet_train([f"run_dir={run_dir}", "resume=true"])
    assert_bitwise_equal(unbroken / "ppo", run_dir)
    assert "nothing to train" in quiet_train([f"run_dir={run_dir}", "resume=true"])
