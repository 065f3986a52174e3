"""The CUDA path (marked ``gpu``; skipped without a CUDA device for torch and Warp, see conftest.py).

The same env code runs on Warp's ``cpu`` and ``cuda`` devices: with the same seed and actions, thousands of envs on
CUDA must step as the CPU steps them (GridWorld exactly: integer moves and the same counter-based RNG; DMC physics
within float32 tolerance over a short horizon, where reduction order differs), the captured step graph must replay
what eager stepping computes, and a training iteration must run end to end on the GPU.

    python -m pytest -m gpu          # on a machine with a CUDA GPU
"""

import json

import pytest
import torch

from refpo_warp import make_env
from refpo_warp.training import train

pytestmark = pytest.mark.gpu
CUDA = "cuda:0"


def rollout(task: str, device: str, num_envs: int, steps: int, seed: int = 3, **env_options):
    """Observations, rewards and dones of ``steps`` steps under fixed random actions (drawn on the CPU, so every
    device gets the same numbers); also the env."""
    env = make_env(task, num_envs=num_envs, device=device, seed=seed, **env_options)
    gen = torch.Generator().manual_seed(0)
    actions = torch.rand(steps, num_envs, env.num_actions, generator=gen) * 2 - 1
    obs, rewards, dones = [], [], []
    for a in actions:
        o, r, d, _ = env.step(a.to(device))
        obs.append(o["policy"].cpu())
        rewards.append(r.cpu())
        dones.append(d.cpu())
    return torch.stack(obs), torch.stack(rewards), torch.stack(dones), env


def test_gridworld_on_cuda_steps_as_on_cpu():
    # 4096 envs, 300 steps: every env ends episodes (200-step time-out, goals) and draws random restarts.
    cuda = rollout("gridworld", CUDA, 4096, 300)
    cpu = rollout("gridworld", "cpu", 4096, 300)
    assert torch.equal(cuda[2], cpu[2])
    assert torch.equal(cuda[0], cpu[0]) and torch.equal(cuda[1], cpu[1])
    assert int(cpu[2].sum()) > 4096, "episodes must end and restart for the check to cover resets"


@pytest.mark.parametrize("task", ["dmc_cartpole_balance", "dmc_pendulum_swingup"])
def test_dmc_on_cuda_steps_as_on_cpu(task):
    cuda = rollout(task, CUDA, 1024, 40)
    cpu = rollout(task, "cpu", 1024, 40)
    torch.testing.assert_close(cuda[0], cpu[0], atol=1e-3, rtol=1e-3)
    torch.testing.assert_close(cuda[1], cpu[1], atol=1e-3, rtol=1e-3)
    assert float((cpu[0][-1] - cpu[0][0]).abs().max()) > 1e-2, "the state must move for the check to mean anything"


@pytest.mark.parametrize("task, exact", [("gridworld", True), ("dmc_cartpole_balance", False)])
def test_captured_cuda_graph_replays_the_eager_step(task, exact):
    captured = rollout(task, CUDA, 2048, 30, graph_capture=True)
    eager = rollout(task, CUDA, 2048, 30, graph_capture=False)
    assert captured[3]._graph is not None and eager[3]._graph is None  # replayed from a CUDA graph vs launched
    if exact:
        assert torch.equal(captured[0], eager[0]) and torch.equal(captured[1], eager[1])
    else:  # MuJoCo Warp may accumulate with atomics: the order of float additions can differ between launches
        torch.testing.assert_close(captured[0], eager[0], atol=1e-5, rtol=1e-5)
        torch.testing.assert_close(captured[1], eager[1], atol=1e-5, rtol=1e-5)


@pytest.mark.parametrize(
    "task, extra",
    [
        ("gridworld", ["num_envs=1024", "runner.num_steps_per_env=32", "eval.num_envs=256", "eval.flow_steps=[1, 10]"]),
        (
            "dmc_cartpole_balance",
            [
                "num_envs=1024",
                "runner.num_steps_per_env=16",
                "eval.num_envs=64",
                "eval.flow_steps=[1]",
                "eval.max_steps=100",
            ],
        ),
    ],
)
def test_one_training_iteration_on_cuda(tmp_path, task, extra):
    run_dir = tmp_path / task
    results = train([f"task={task}", "algo=refpo", f"device={CUDA}", "max_iterations=1", f"run_dir={run_dir}", *extra])
    rows = [json.loads(line) for line in (run_dir / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0]
    assert all(torch.isfinite(torch.tensor(v)) for k, v in rows[0].items() if k.startswith(("Loss/", "Flow/")))
    saved = torch.load(run_dir / "model_0.pt", weights_only=True, map_location="cpu")
    assert saved["iter"] == 0
    for setting, summary in results["results"].items():
        assert summary["episodes"] > 0 and torch.isfinite(torch.tensor(summary["return_mean"])), setting
    assert json.loads((run_dir / "eval.json").read_text())["results"] == results["results"]
