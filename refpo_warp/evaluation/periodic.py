"""Evaluation during training, between the runner's chunks (``refpo_warp/training/train_run.py``): every
``eval.interval`` iterations the returns at ``eval.interval_flow_steps`` under each ``eval.initial_noise`` protocol
(``eval/return_N<n>``, ``eval/return_N<n>_zero``, or ``eval/return`` for a Gaussian actor) and, for flows, the
Jacobian statistics (``Flow/jacobian_*``) on the visited observations.

An evaluation draws from random streams of its own, seeded from the run's seed and the iteration
(``refpo_warp.utils.rng``), and reads the policy without updating its normaliser: a run trains the same, bit for
bit, with any ``eval.interval``."""

from __future__ import annotations

from refpo_warp.evaluation.evaluate_policy import curve_key, evaluate_actor, is_flow, make_eval_envs
from refpo_warp.models.flow_diagnostics import jacobian_statistics
from refpo_warp.utils.rng import PERIODIC_EVALUATION, own_random_streams, stream_seed

RECORDED_OBSERVATIONS = 256  # visited observations kept for the Jacobian statistics


def periodic_evaluator(cfg: dict, runner):
    """``evaluate(iteration, is_last) -> {name: value}`` for the iterations an evaluation is due at ({} otherwise)."""
    envs = make_eval_envs(cfg, interval=True)
    interval = int(cfg["eval"]["interval"])

    def evaluate(it: int, is_last: bool) -> dict[str, float]:
        if (it + 1) % interval and not is_last:
            return {}
        actor = runner.alg.get_policy()
        was_training = actor.training
        actor.eval()
        flow = is_flow(actor)
        with own_random_streams(stream_seed(cfg["seed"], PERIODIC_EVALUATION, it), runner.device):
            results, visited = evaluate_actor(
                cfg, actor, envs, cfg["eval"]["interval_flow_steps"], record_obs=RECORDED_OBSERVATIONS if flow else 0
            )
            out = {curve_key(name): s.get("return_mean", float("nan")) for name, s in results.items()}
            if flow and visited is not None and hasattr(actor, "velocity"):
                stats = jacobian_statistics(actor, visited, num_steps=actor.num_flow_steps)
                out.update({f"Flow/{k}": v for k, v in stats.items() if isinstance(v, float)})
        actor.train(was_training)
        return out

    return evaluate
