"""What differs between the supported rsl-rl-lib versions (refpo_warp/utils/rsl_rl_versions.py), checked on the
installed one: CI runs this file on 5.0.1 (Isaac Lab's pin) and on the newest 5.x."""

import copy
import warnings

import pytest
import torch
from rsl_rl.runners import OnPolicyRunner

from refpo_warp import make_env
from refpo_warp.utils.device import cpu_has_native_bfloat16
from refpo_warp.utils.rsl_rl_versions import NORMALIZERS_UPDATE_PER_STEP, RSL_RL_VERSION

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

NUM_ENVS, STEPS = 8, 16


def train_cfg(algorithm: dict, actor: dict) -> dict:
    algorithm, actor = copy.deepcopy(algorithm), copy.deepcopy(actor)  # rsl_rl < 5.5 pops class_name from them
    return {
        "num_steps_per_env": STEPS,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"hidden_dims": [16], "obs_normalization": True, **actor},
        "critic": {"class_name": "MLPModel", "hidden_dims": [16], "obs_normalization": True},
        "algorithm": {"num_learning_epochs": 1, "num_mini_batches": 2, "schedule": "fixed", **algorithm},
    }


FLOW = (
    {"class_name": "refpo_warp.algorithms:ReFPO", "num_mc_samples": 2},
    {"class_name": "refpo_warp.models:FlowActor"},
)
GAUSSIAN = (
    {"class_name": "refpo_warp.algorithms:PPO"},
    {"class_name": "MLPModel", "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": 1.0}},
)


def test_version_flags_agree_with_the_installed_package():
    assert (5, 0) <= RSL_RL_VERSION < (6, 0)
    assert (RSL_RL_VERSION < (5, 5)) == NORMALIZERS_UPDATE_PER_STEP


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
    # refpo_warp's update loop applies mixed precision itself, so no rsl_rl version ignores it
    assert runner.alg.use_mixed_precision is True
    assert not [w for w in caught if "has no PPO argument 'use_mixed_precision'" in str(w.message)]
    slow = [w for w in caught if "without native bfloat16" in str(w.message)]
    assert len(slow) == (0 if cpu_has_native_bfloat16() else 1)  # the emulated bfloat16 is named, where it is
    assert not [w for w in caught if "grad_reduce_bucket_mb" in str(w.message)]  # the default value: no warning
    runner.learn(1)


def test_unsupported_newer_argument_values_warn_on_older_versions():
    from refpo_warp.utils.rsl_rl_versions import split_newer_ppo_args

    kwargs = {"clip_param": 0.1, "grad_reduce_bucket_mb": 50, "use_mixed_precision": True}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        newer = split_newer_ppo_args(kwargs, honoured=("use_mixed_precision",))
    if RSL_RL_VERSION >= (5, 5):  # accepted by rsl_rl itself: nothing taken out
        assert newer == {} and len(kwargs) == 3 and not caught
    else:
        assert newer == {"grad_reduce_bucket_mb": 50, "use_mixed_precision": True} and kwargs == {"clip_param": 0.1}
        assert [str(w.message).split("'")[1] for w in caught] == ["grad_reduce_bucket_mb"]


def test_fixed_gaussian_std_on_every_version():
    """``learn_std: false`` (rsl-rl-lib >= 5.2) also fixes the std of a PhcMLPModel on older versions."""
    env = make_env("gridworld", num_envs=NUM_ENVS, device="cpu", seed=0)
    actor = {
        "class_name": "refpo_warp.models:PhcMLPModel",
        "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": 0.3, "learn_std": False},
    }
    cfg = train_cfg({"class_name": "refpo_warp.algorithms:PPO", "learning_rate": 1e-2}, actor)
    runner = OnPolicyRunner(env, cfg, log_dir=None, device="cpu")
    runner.learn(2)
    assert torch.allclose(runner.alg.actor.output_std, torch.full((2,), 0.3))
    assert cfg["actor"]["distribution_cfg"]["learn_std"] is False  # the caller's dict keeps its keys
