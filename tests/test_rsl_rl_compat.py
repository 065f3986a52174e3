"""What differs between the supported rsl-rl-lib versions (refpo_warp/rsl_rl_compat.py), checked on the installed
one: CI runs this file on 5.0.1 (Isaac Lab's pin) and on the newest 5.x."""

import warnings

import pytest
import torch
from rsl_rl.runners import OnPolicyRunner

from refpo_warp import make_env
from refpo_warp.rsl_rl_compat import NORMALIZERS_UPDATE_PER_STEP, RSL_RL_VERSION

NUM_ENVS, STEPS = 8, 16


def train_cfg(algorithm: dict, actor: dict) -> dict:
    return {
        "num_steps_per_env": STEPS, "save_interval": 100, "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"hidden_dims": [16], "obs_normalization": True, **actor},
        "critic": {"class_name": "MLPModel", "hidden_dims": [16], "obs_normalization": True},
        "algorithm": {"num_learning_epochs": 1, "num_mini_batches": 2, "schedule": "fixed", **algorithm},
    }  # fmt: skip


FLOW = ({"class_name": "refpo_warp.algorithms:ReFPO", "num_mc_samples": 2},
        {"class_name": "refpo_warp.models:FlowActor"})
GAUSSIAN = ({"class_name": "refpo_warp.algorithms:PPO"},
            {"class_name": "MLPModel", "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": 1.0}})


def test_version_flags_agree_with_the_installed_package():
    assert (5, 0) <= RSL_RL_VERSION < (6, 0)
    assert NORMALIZERS_UPDATE_PER_STEP == (RSL_RL_VERSION < (5, 5))


def test_refpo_normalisers_see_every_observation_once():
    """Whether rsl_rl updates normalisers per env step (< 5.5) or per update, ReFPO adds nothing on top."""
    torch.manual_seed(0)
    env = make_env("gridworld", num_envs=NUM_ENVS, device="cpu", seed=0)
    runner = OnPolicyRunner(env, train_cfg(*FLOW), log_dir=None, device="cpu")
    runner.learn(2)
    for model in (runner.alg.actor, runner.alg.critic):
        assert int(model.obs_normalizer.count) == 2 * NUM_ENVS * STEPS


@pytest.mark.parametrize("algorithm, actor", [FLOW, GAUSSIAN], ids=["refpo", "ppo"])
def test_newer_ppo_arguments_are_accepted(algorithm, actor):
    env = make_env("gridworld", num_envs=NUM_ENVS, device="cpu", seed=0)
    cfg = train_cfg({**algorithm, "use_mixed_precision": True, "grad_reduce_bucket_mb": 25}, actor)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runner = OnPolicyRunner(env, cfg, log_dir=None, device="cpu")
    ignored = [w for w in caught if "use_mixed_precision" in str(w.message)]
    # ReFPO's own update applies mixed precision on every version; rsl_rl's PPO update only from 5.5 on.
    assert runner.alg.use_mixed_precision is True
    assert len(ignored) == int(algorithm is GAUSSIAN[0] and RSL_RL_VERSION < (5, 5))
    assert not [w for w in caught if "grad_reduce_bucket_mb" in str(w.message)]  # the default value: no warning
    runner.learn(1)
