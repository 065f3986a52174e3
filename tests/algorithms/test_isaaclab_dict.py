"""The Isaac Lab field-by-field dict of docs/rsl_rl_users.md trains ReFPO with rsl_rl's plain OnPolicyRunner
(CI runs this on rsl-rl-lib 5.0.1, Isaac Lab's pin, and on the newest 5.x)."""

import copy
import re
import warnings

import pytest
import torch
from rsl_rl.runners import OnPolicyRunner

from refpo_warp import make_env
from refpo_warp.algorithms import ReFPO
from refpo_warp.models import FlowActor
from refpo_warp.utils.paths import REPO_ROOT

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

DOC = REPO_ROOT / "docs" / "rsl_rl_users.md"


def documented_train_cfg() -> dict:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.DOTALL)
    block = next(b for b in blocks if "train_cfg = {" in b)
    namespace: dict = {}
    exec(block, namespace)
    return namespace["train_cfg"]


def test_isaaclab_dict_trains_refpo_with_the_plain_runner(tmp_path):
    train_cfg = documented_train_cfg()
    assert train_cfg["actor"]["class_name"] == "refpo_warp.models:FlowActor"
    assert train_cfg["algorithm"]["class_name"] == "refpo_warp.algorithms:ReFPO"
    cfg = copy.deepcopy(train_cfg)
    cfg["device"] = "cpu"  # the only change: Isaac Lab's default is cuda:0
    torch.manual_seed(cfg["seed"])
    env = make_env("gridworld", num_envs=16, device=cfg["device"], seed=cfg["seed"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)  # the recommended values draw none (entropy, schedule, ...)
        runner = OnPolicyRunner(env, cfg, log_dir=str(tmp_path), device=cfg["device"])
    assert isinstance(runner.alg, ReFPO) and isinstance(runner.alg.actor, FlowActor)
    before = {k: v.clone() for k, v in runner.alg.actor.state_dict().items()}
    runner.learn(2, init_at_random_ep_len=cfg["init_at_random_ep_len"])
    after = runner.alg.actor.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in before), "two updates changed no actor parameter"
    assert all(torch.isfinite(v).all() for v in after.values())
    assert runner.alg.learning_rate == cfg["algorithm"]["learning_rate"]  # fixed schedule
    assert sorted(p.name for p in tmp_path.glob("model_*.pt")) == ["model_0.pt", "model_1.pt"]
    loaded = torch.load(tmp_path / "model_1.pt", weights_only=False)
    assert {"actor_state_dict", "critic_state_dict", "optimizer_state_dict"} <= set(loaded)
