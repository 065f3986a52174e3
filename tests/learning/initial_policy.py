"""The return of the policy a training run starts from: the learning checks compare their result with it."""

import contextlib
import io

from refpo_warp.config.resolve import resolve_config
from refpo_warp.evaluation.evaluate_policy import evaluate_actor, make_eval_env
from refpo_warp.runner.build import build_runner, seed_everything


def initial_returns(overrides: list[str], flow_steps: list[int]) -> dict[int, float]:
    """Evaluation return per flow-step count of the policy that training with ``overrides`` starts from (same seed,
    same construction, the run's own evaluation protocol)."""
    cfg = resolve_config(overrides)
    seed_everything(cfg["seed"])
    with contextlib.redirect_stdout(io.StringIO()):
        _, runner = build_runner(cfg, None)
    actor = runner.alg.get_policy().eval()
    results, _ = evaluate_actor(cfg, actor, make_eval_env(cfg), list(flow_steps))
    return {n: results[f"N={n}"]["return_mean"] for n in flow_steps}
