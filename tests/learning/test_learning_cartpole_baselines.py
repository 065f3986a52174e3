"""Learning checks of the issue-10 methods: Flow-GRPO, ReinFlow and the advantage-weighted ReFPO each raise their
evaluation return on dmc_cartpole_balance to at least twice the initial policy's and to at least 500.

Each uses the task's CPU profile as shipped (configs/task/dmc_cartpole_balance.yaml, ``by_device.cpu.by_algo``) and the
final evaluation of tools/train.py: Flow-GRPO and the weighted ReFPO by the deterministic ODE at N = 10, ReinFlow by
its deterministic chain at K = 4. The initial policy (same seed, same construction) is evaluated the same way first.
The checks run on conftest's one torch thread whether or not xdist runs them (CI: -n 2): these runs depend on the
order of floating-point sums, so they run exactly as measured.
"""

import contextlib
import io

import pytest

from refpo_warp.config.resolve import resolve_config
from refpo_warp.evaluation.evaluate_policy import evaluate_actor, make_eval_env
from refpo_warp.runner.build import build_runner, seed_everything
from refpo_warp.training import train


def initial_return(overrides: list[str], flow_steps: int) -> float:
    """The evaluation return of the policy that training with ``overrides`` starts from."""
    cfg = resolve_config(overrides)
    seed_everything(cfg["seed"])
    with contextlib.redirect_stdout(io.StringIO()):
        _, runner = build_runner(cfg, None)
    actor = runner.alg.get_policy().eval()
    results, _ = evaluate_actor(cfg, actor, make_eval_env(cfg), [flow_steps])
    return results[f"N={flow_steps}"]["return_mean"]


CHECKS = [("flow_grpo", 10), ("reinflow", 4), ("refpo_aw", 10)]


@pytest.mark.slow
@pytest.mark.parametrize("algo, flow_steps", CHECKS)
def test_method_raises_its_cartpole_return(algo, flow_steps, tmp_run_dir):
    overrides = ["task=dmc_cartpole_balance", f"algo={algo}", "seed=1", "device=cpu", f"run_dir={tmp_run_dir}"]
    before = initial_return(overrides, flow_steps)
    results = train(overrides)
    after = results["results"][f"N={flow_steps}"]
    print(f"[learning check] {algo}: N={flow_steps} return {before:.1f} -> {after['return_mean']:.1f}", flush=True)
    assert after["return_mean"] >= max(500.0, 2.0 * before), (before, after)
    assert after["nonfinite_resets_mean"] == 0 and (tmp_run_dir / "eval.json").exists()
