"""docs/create_new_task.md, followed step by step: a tiny task (its options, env, declaration and config file) and a
ReFPO variant, registered here and trained for one iteration, and a task's own options (a second line task; the
page's DMC example, which is the tree's code). The code below is the page's code."""

from dataclasses import dataclass

import pytest

from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.envs.warp_vec_env import WarpVecEnv
from refpo_warp.utils.option_rules import Real
from refpo_warp.utils.options import option
from refpo_warp.utils.warp_setup import wp


# --- 1. the task: options (tasks/line/cfg.py)
@dataclass
class LineCfg(EnvCfg):
    speed: float = option(0.1, Real(0, 10, lo_open=True), "distance moved per step at action 1")
    max_episode_length: int = option(20)  # another default for EnvCfg's option, which keeps its rule and doc


# --- env (tasks/line/env.py)
@wp.kernel
def line_step(
    actions: wp.array2d(dtype=float),
    pos: wp.array(dtype=float),
    speed: float,
    rewards: wp.array(dtype=float),
    terminated: wp.array(dtype=wp.bool),
):
    i = wp.tid()
    x = pos[i] + speed * wp.clamp(actions[i, 0], -1.0, 1.0)
    pos[i] = x
    rewards[i] = 1.0 - wp.abs(x)
    terminated[i] = wp.abs(x) > 1.0  # left the line: a failure, not a time-out


@wp.kernel
def line_reset(
    mask: wp.array(dtype=wp.bool),
    rng: wp.array(dtype=wp.uint32),
    pos: wp.array(dtype=float),
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    if mask[i]:
        state = rng[i]
        pos[i] = wp.randf(state, -0.5, 0.5)
        rng[i] = state
    obs[i, 0] = pos[i]


class LineEnv(WarpVecEnv):
    cfg_class = LineCfg

    def _spaces(self):
        return 1, {"policy": 1}  # action size, {observation group: size}

    def _build(self):
        self.pos = wp.zeros(self.num_envs, dtype=float, device=self.wp_device)

    def _step_impl(self):
        b = self.buffers
        wp.launch(
            line_step,
            dim=self.num_envs,
            inputs=[b.actions, self.pos, self.cfg.speed],
            outputs=[b.rewards, b.terminated],
        )

    def _reset_impl(self, mask):
        b = self.buffers
        wp.launch(line_reset, dim=self.num_envs, inputs=[mask, b.rng, self.pos], outputs=[b.obs["policy"]])


# --- 2. the algorithm (refpo_warp/algorithms/<name>.py)
class CappedReflowReFPO(ReFPO):
    """ReFPO whose Reflow term averages min(l_i, reflow_cap) over the actions' CFM losses l_i."""

    # each option once: its type, its default, its rule, its meaning
    reflow_cap: float = option(1.0, Real(0, 1e6, lo_open=True), "the cap on each action's CFM loss")

    def reflow_loss(self, new_loss, batch):
        return new_loss.mean(dim=-1).clamp(max=self.reflow_cap).mean()


CONFIG = """num_envs: 8
runner: {num_steps_per_env: 16}
eval: {num_envs: 8, flow_steps: [1, 2]}
"""


@pytest.fixture
def line_task(tmp_path):
    """The declaration (here by register_task, as code outside tasks/ does) and its config file."""
    from refpo_warp.envs.registry import _TASKS, register_task

    (tmp_path / "line.yaml").write_text(CONFIG)
    register_task(
        TaskSpec(
            "line",
            f"{__name__}:LineEnv",
            LineCfg,
            description="stay near 0 on a line",
            config_file=tmp_path / "line.yaml",
        )
    )
    yield tmp_path
    del _TASKS["line"]


def test_the_env_follows_the_base_episode_rules(line_task):
    import torch

    from refpo_warp.envs.registry import make_env

    env = make_env("line", num_envs=4, device="cpu", seed=0, speed=0.5)
    ended = torch.zeros(4)
    for _ in range(3):  # x0 in [-0.5, 0.5], +0.5 a step: each env leaves the line once (step 2 or 3), and a
        _, _, dones, extras = env.step(torch.ones(4, 1))  # restarted env cannot leave again within one step
        assert not extras["time_outs"].any()  # a failure, not a time-out
        ended += dones
    assert (ended == 1).all()
    assert (env.episode_length_buf <= 1).all()  # restarted by the base env
    env.reset()
    for _ in range(19):  # standing still: the 20-step time-out ends every episode, reported as a time-out
        _, _, dones, _ = env.step(torch.zeros(4, 1))
        assert not dones.any()
    _, _, dones, extras = env.step(torch.zeros(4, 1))
    assert dones.all() and extras["time_outs"].all() and (env.episode_length_buf == 0).all()


def test_the_new_task_and_algorithm_train_one_iteration(line_task):
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.training import train

    run_dir = line_task / "run"
    results = train(
        [
            "task=line",
            "algo=refpo",
            "device=cpu",
            "max_iterations=1",
            f"run_dir={run_dir}",
            f"algorithm.class_name={__name__}:CappedReflowReFPO",
            "algorithm.reflow_cap=0.5",
            "algorithm.num_mc_samples=4",
        ]
    )
    (row,) = read_rows(run_dir)
    assert row["env_steps"] == 8 * 16 and 0.0 <= row["Loss/reflow"] <= 0.5
    assert (run_dir / "model_0.pt").is_file() and set(results["results"]) == {"N=1", "N=2"}
    with pytest.raises(Exception, match="reflow_cap"):  # the option's rule is checked at config time
        train(
            [
                "task=line",
                "device=cpu",
                f"run_dir={line_task / 'bad'}",
                f"algorithm.class_name={__name__}:CappedReflowReFPO",
                "algorithm.reflow_cap=-1",
            ]
        )


ALGO_FILE = """# ReFPO with its Reflow term capped per action (refpo_warp/algorithms/capped_reflow.py)
base: refpo
algorithm: {class_name: refpo_warp.algorithms:CappedReflowReFPO}
"""


def test_an_algo_file_derived_from_refpo_takes_every_tasks_refpo_settings(tmp_path):
    """The page's algo file in a config folder of one's own (REFPO_CONFIG_PATH), explained by tools/train.py in a
    fresh process; the class is this module's, under the name the page gives it."""
    import os
    import subprocess
    import sys

    from refpo_warp.utils.paths import REPO_ROOT

    configs = tmp_path / "my_configs"
    (configs / "algo").mkdir(parents=True)
    (configs / "algo" / "capped_reflow.yaml").write_text(ALGO_FILE.replace("refpo_warp.algorithms:", f"{__name__}:"))
    env = {
        **os.environ,
        "REFPO_CONFIG_PATH": str(configs),
        "PYTHONPATH": os.pathsep.join([os.path.dirname(__file__), os.environ.get("PYTHONPATH", "")]),
    }
    proc = subprocess.run(
        [
            sys.executable,
            "tools/train.py",
            "task=gridworld",
            "algo=capped_reflow",
            "--explain",
            "algorithm.reflow_cap,algorithm.reflow_coef,algorithm.num_mc_samples",
        ],
        cwd=REPO_ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert (
        f"  6. {configs / 'algo' / 'capped_reflow.yaml'}\n" in out
    )  # after the run options' defaults and default.yaml
    assert f"algorithm.reflow_cap = 1.0\n  set by  the default of {__name__}.CappedReflowReFPO" in out
    assert "  means   the cap on each action's CFM loss" in out
    assert "algorithm.reflow_coef = 0.1\n  set by  configs/task/gridworld.yaml by_algo.refpo" in out
    assert "algorithm.num_mc_samples = 50" in out


# --- a task's own options: a subclass of the family's cfg, named by that task's TaskSpec
@dataclass
class FarLineCfg(LineCfg):
    start_range: float = option(0.9, Real(0, 1), "half the range of the start")


def test_a_tasks_own_option_is_accepted_by_that_task_only(line_task):
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.envs.registry import _TASKS, register_task
    from refpo_warp.utils.errors import ConfigError

    register_task(TaskSpec("line_far", f"{__name__}:LineEnv", FarLineCfg, config_file=line_task / "line.yaml"))
    try:
        cfg = resolve_config(["task=line_far", "algo=refpo", "device=cpu", "env.start_range=0.5"], device_type="cpu")
        assert cfg["env"] == {"start_range": 0.5}
        with pytest.raises(ConfigError, match=r"'env\.start_range': an env option of line_far only"):
            resolve_config(["task=line", "algo=refpo", "device=cpu", "env.start_range=0.5"], device_type="cpu")
    finally:
        del _TASKS["line_far"]


def test_the_pages_dmc_example_is_the_code_and_does_what_it_says():
    import re

    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.utils.errors import ConfigError
    from refpo_warp.utils.paths import REPO_ROOT

    page = (REPO_ROOT / "docs" / "create_new_task.md").read_text(encoding="utf-8")
    (example,) = [b for b in re.findall(r"```python\n(.*?)```", page, re.DOTALL) if "class CheetahRunCfg" in b]
    assert example in (REPO_ROOT / "tasks" / "dmc" / "cheetah_run_cfg.py").read_text(encoding="utf-8")
    ok = resolve_config(["task=dmc_cheetah_run", "algo=ppo", "device=cpu", "env.reset_bank_size=512"], "cpu")
    assert ok["env"] == {"reset_bank_size": 512}
    with pytest.raises(ConfigError, match=r"'env\.reset_bank_size': an env option of dmc_cheetah_run only"):
        resolve_config(["task=dmc_walker_walk", "algo=ppo", "device=cpu", "env.reset_bank_size=512"], "cpu")
