"""The ReFPO variants that the mjlab.tasks entry point registers: ids, configs (a flow actor of the task's sizes,
ReFPO's own settings, the task's other PPO keys), runner classes, CLI flags, a user's own task, export.

Needs mjlab (skipped without it): run in the mjlab job's venv, ``.ci/mjlab`` (docs/mjlab.md)."""

from dataclasses import asdict, fields, replace

import pytest

pytest.importorskip("mjlab", reason="mjlab is not installed: run in the mjlab venv (.ci/mjlab, docs/mjlab.md)")

import torch
from mjlab.rl import MjlabOnPolicyRunner, RslRlPpoAlgorithmCfg
from mjlab.tasks.registry import list_tasks, load_env_cfg, load_rl_cfg, load_runner_cls, register_mjlab_task

from refpo_warp.config.classes import class_defaults
from refpo_warp.integrations.mjlab import REFPO_SUFFIX, VARIANT_BASES, refpo_runner_cls, register_refpo_variant
from refpo_warp.integrations.mjlab.cfg import ACTOR_CLASS, ALGORITHM_CLASS, REFPO_PPO_KEYS, refpo_runner_cfg
from refpo_warp.integrations.statistics_logger import StatisticsRunnerMixin

REQUIRED = [
    "Mjlab-Cartpole-Balance",
    "Mjlab-Cartpole-Swingup",
    "Mjlab-Velocity-Flat-Unitree-G1",
    "Mjlab-Velocity-Flat-Unitree-Go1",
    "Mjlab-Tracking-Flat-Unitree-G1",
]


def test_the_entry_point_registers_the_variants():
    tasks = list_tasks()
    assert set(REQUIRED) <= set(VARIANT_BASES)
    assert all(base + REFPO_SUFFIX in tasks for base in VARIANT_BASES), tasks


@pytest.mark.parametrize("base", VARIANT_BASES)
def test_the_one_step_variant_is_the_refpo_variant_with_the_one_step_configurations_options(base):
    import yaml

    from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR

    refpo, onestep = load_rl_cfg(base + REFPO_SUFFIX), load_rl_cfg(base + REFPO_SUFFIX + "-OneStep")
    options = yaml.safe_load((PACKAGED_CONFIG_DIR / "algo" / "refpo_onestep.yaml").read_text())["algorithm"]
    assert options and all(getattr(onestep.algorithm, k) == v for k, v in options.items()), options
    assert replace(onestep.algorithm, **{k: getattr(refpo.algorithm, k) for k in options}) == refpo.algorithm
    assert onestep.actor == refpo.actor and onestep.experiment_name == refpo.experiment_name + "_onestep"


@pytest.mark.parametrize("base", VARIANT_BASES)
def test_a_variant_is_the_task_with_a_flow_actor_and_refpo(base):
    ppo, refpo = load_rl_cfg(base), load_rl_cfg(base + REFPO_SUFFIX)
    assert refpo.actor.class_name == ACTOR_CLASS and refpo.algorithm.class_name == ALGORITHM_CLASS
    assert (refpo.actor.hidden_dims, refpo.actor.activation, refpo.actor.obs_normalization) == (
        tuple(ppo.actor.hidden_dims),
        ppo.actor.activation,
        ppo.actor.obs_normalization,
    )
    assert refpo.actor.distribution_cfg is None and refpo.critic == ppo.critic
    defaults = class_defaults(ALGORITHM_CLASS)
    assert set(REFPO_PPO_KEYS) == {"clip_param", "learning_rate", "schedule", "entropy_coef", "use_clipped_value_loss"}
    for key in REFPO_PPO_KEYS:  # ReFPO's own values, from its constructor
        assert getattr(refpo.algorithm, key) == defaults[key][0], key
    assert refpo.algorithm.schedule == "fixed" and refpo.algorithm.entropy_coef == 0.0
    for f in fields(RslRlPpoAlgorithmCfg):  # every other PPO key is the task's
        if f.name not in REFPO_PPO_KEYS and f.name != "class_name":
            assert getattr(refpo.algorithm, f.name) == getattr(ppo.algorithm, f.name), f.name
    assert refpo.algorithm.reflow_coef == defaults["reflow_coef"][0]
    assert refpo.algorithm.num_mc_samples == defaults["num_mc_samples"][0]
    assert refpo.actor.num_flow_steps == class_defaults(ACTOR_CLASS)["num_flow_steps"][0]
    assert (refpo.num_steps_per_env, refpo.max_iterations, refpo.obs_groups) == (
        ppo.num_steps_per_env,
        ppo.max_iterations,
        ppo.obs_groups,
    )
    assert refpo.experiment_name == ppo.experiment_name + "_refpo"
    runner, base_runner = load_runner_cls(base + REFPO_SUFFIX), load_runner_cls(base) or MjlabOnPolicyRunner
    assert issubclass(runner, StatisticsRunnerMixin) and issubclass(runner, base_runner)


def test_a_variant_config_pickles():
    """mjlab's multi-GPU launcher (torchrunx) pickles the train config to its workers."""
    import pickle

    cfg = load_rl_cfg("Mjlab-Velocity-Flat-Unitree-G1" + REFPO_SUFFIX)
    assert pickle.loads(pickle.dumps(cfg)) == cfg


def test_train_flags_reach_refpo_and_the_flow_actor():
    import tyro
    from mjlab.scripts.train import TrainConfig

    task = "Mjlab-Cartpole-Balance" + REFPO_SUFFIX
    args = tyro.cli(
        TrainConfig,
        default=TrainConfig.from_task(task),
        config=__import__("mjlab").TYRO_FLAGS,
        args=[
            "--agent.algorithm.reflow-coef",
            "0.1",
            "--agent.actor.num-flow-steps",
            "3",
            "--agent.algorithm.tau-sampling",
            "discrete",
        ],
    )
    agent = asdict(args.agent)
    assert agent["algorithm"]["reflow_coef"] == 0.1 and agent["algorithm"]["tau_sampling"] == "discrete"
    assert agent["actor"]["num_flow_steps"] == 3 and agent["algorithm"]["schedule"] == "fixed"


def test_a_users_task_gets_a_variant_and_bad_ones_are_named():
    register_mjlab_task(
        "Test-User-Cartpole",
        env_cfg=load_env_cfg("Mjlab-Cartpole-Balance"),
        play_env_cfg=load_env_cfg("Mjlab-Cartpole-Balance", play=True),
        rl_cfg=load_rl_cfg("Mjlab-Cartpole-Balance"),
    )
    assert register_refpo_variant("Test-User-Cartpole") == "Test-User-Cartpole-ReFPO"
    assert load_rl_cfg("Test-User-Cartpole-ReFPO").algorithm.class_name == ALGORITHM_CLASS
    assert load_runner_cls("Test-User-Cartpole-ReFPO") is refpo_runner_cls(None)
    with pytest.raises(KeyError, match=r"'Test-Missing' is not a registered mjlab task; registered: .*Mjlab-Cartpole"):
        register_refpo_variant("Test-Missing")
    vision = load_rl_cfg("Mjlab-Lift-Cube-Yam-Rgb")
    with pytest.raises(ValueError, match="FlowActor is an MLP"):
        refpo_runner_cfg(vision)
    with pytest.raises(TypeError, match="MjlabOnPolicyRunner"):
        refpo_runner_cls(dict)


@pytest.mark.rsl_rl
def test_the_onnx_policy_takes_the_observation_only_and_matches_the_actor(tmp_path):
    """mjlab's runners export ``alg.get_policy().as_onnx()`` (the velocity and tracking runners on every save): for a
    flow actor that is the deterministic N-step sampler with the single input ``obs``."""
    import onnx
    from mjlab.envs import ManagerBasedRlEnv
    from mjlab.rl import RslRlVecEnvWrapper
    from onnx.reference import ReferenceEvaluator

    task = "Mjlab-Cartpole-Balance" + REFPO_SUFFIX
    env_cfg = load_env_cfg(task, play=True)
    env_cfg.scene.num_envs = 2
    env = RslRlVecEnvWrapper(ManagerBasedRlEnv(cfg=env_cfg, device="cpu"))
    try:
        runner = load_runner_cls(task)(env, asdict(load_rl_cfg(task)), device="cpu")
        runner.export_policy_to_onnx(str(tmp_path), "policy.onnx")
        model = onnx.load(tmp_path / "policy.onnx")
        assert [i.name for i in model.graph.input] == ["obs"] and [o.name for o in model.graph.output] == ["actions"]
        obs = env.get_observations()
        policy = runner.get_inference_policy("cpu")
        with torch.inference_mode():
            expected = policy(obs).numpy()
        flat = obs["actor"][:1].numpy()
        (actions,) = ReferenceEvaluator(model).run(None, {"obs": flat})
        assert actions.shape == (1, 1)
        torch.testing.assert_close(torch.from_numpy(actions), torch.from_numpy(expected[:1]), atol=1e-5, rtol=1e-5)
    finally:
        env.close()
