"""Goal-conditioning masks: which policy-observation entries each regime hides (the critic always sees all)."""

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.tasks.humanoid.obs_layout import OBS_DIM, SELF_DIM, block_slice, conditioning_mask

# Hand-worked indices. Self part: 1 + 23*3 + 24*6 + 24*3 + 24*3 = 358. Task blocks start at 358 (position
# difference, 24*3), 430 (rotation difference, 24*6), 574 (velocity difference), 646 (angular-velocity
# difference), 718 (reference position, 24*3), 790 (reference rotation, 24*6). Pelvis = body 0, L_Wrist = 17,
# R_Wrist = 22.
PELVIS = [358, 359, 360, 718, 719, 720]
WRISTS = [
    358 + 51,
    358 + 52,
    358 + 53,
    358 + 66,
    358 + 67,
    358 + 68,
    718 + 51,
    718 + 52,
    718 + 53,
    718 + 66,
    718 + 67,
    718 + 68,
]


def test_layout_sizes():
    assert (OBS_DIM, SELF_DIM) == (934, 358)
    assert block_slice("diff_pos", 17) == slice(409, 412) and block_slice("ref_pos", 22) == slice(784, 787)
    assert block_slice("ref_rot") == slice(790, 934) and block_slice("body_pos", 1) == slice(1, 4)


@pytest.mark.parametrize(
    "regime, kept_task",
    [("all", list(range(358, 934))), ("root_hands", PELVIS + WRISTS), ("root", PELVIS)],
)
def test_mask_keeps_self_part_and_exactly_the_conditioned_targets(regime, kept_task):
    mask = conditioning_mask(regime)
    expected = np.zeros(934)
    expected[:358] = 1
    expected[kept_task] = 1
    np.testing.assert_array_equal(mask, expected)


def test_unknown_regime_is_a_clear_error():
    with pytest.raises(ValueError, match="root_hands"):
        conditioning_mask("hands")


@pytest.mark.parametrize(
    "task, kept", [("humanoid_all", 934), ("humanoid_root_hands", 358 + 18), ("humanoid_root", 358 + 6)]
)
def test_env_policy_obs_hides_exactly_the_masked_entries(task, kept):
    env = make_env(task, num_envs=2, device="cpu", seed=1)
    obs, _, _, _ = env.step(0.1 * torch.ones(2, 69))
    policy, critic = obs["policy"].numpy(), obs["critic"].numpy()
    mask = conditioning_mask(env.cfg.conditioning).astype(bool)
    assert mask.sum() == kept
    np.testing.assert_array_equal(policy[:, mask], critic[:, mask])
    assert not policy[:, ~mask].any()
    if kept < 934:  # hidden from the policy, present for the critic
        assert np.count_nonzero(critic[:, ~mask]) > 0.9 * critic[:, ~mask].size
