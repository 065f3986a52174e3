"""dmc_point_mass_wall and its scripted demonstrator (CPU): the wall stops the mass (MuJoCo contacts, vs MuJoCo C and
the hand-worked rest position), the options size the wall and refuse a closed arena (exit 2), rewards vs hand-worked
values and an independent path-length reference, the resets, the demonstrator's two ways and mix, the mean of the
two ways ending against the wall, and refpo collect writing a dataset."""

import math

import mujoco
import numpy as np
import pytest
import torch
from dmc_mujoco_reference import wall_path_length
from scipy.stats import binomtest

from refpo_warp.cli.main import main
from refpo_warp.demonstrations.collect import collect
from refpo_warp.envs.registry import get_task, make_env, make_env_cfg
from refpo_warp.tasks.dmc.demonstrator import make_demonstrator
from refpo_warp.tasks.dmc.point_mass_wall_cfg import PointMassWallCfg
from refpo_warp.utils.errors import ConfigError

TASK = "dmc_point_mass_wall"
N = 128  # one env for every test below; enough episodes to see the demonstrator's mix
TARGET = torch.tensor([0.2, 0.0])
A, B = 0.03, 0.16  # the default wall (half-thickness 0.02, half-length 0.15) grown by the mass's radius 0.01
PUSH = 4.0  # pre-tanh action: tanh(4) = 0.9993 of the motor's range


@pytest.fixture(scope="module")
def env():
    return make_env(TASK, num_envs=N, device="cpu", seed=3)


def put(env, positions):
    """A fresh episode in every env, at rest at ``positions`` (cycled over the envs)."""
    env.reset()
    pos = torch.tensor(positions, dtype=torch.float32)[torch.arange(env.num_envs) % len(positions)]
    env.set_state(pos, torch.zeros_like(pos))


def test_the_task_id_fixes_its_cfg_and_options():
    spec = get_task(TASK)
    assert spec.cfg_class is PointMassWallCfg and spec.cfg_overrides == {"task": "point_mass_wall"}
    cfg = make_env_cfg(TASK)
    assert (cfg.wall_half_length, cfg.wall_half_thickness, cfg.start_spread) == (0.15, 0.02, 0.02)
    assert cfg.wall_box() == pytest.approx((A, B)) and cfg.max_episode_length == 1000
    assert cfg.action_transform == "tanh"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["env.wall_half_length=0.29"], "env.wall_half_length=0.29 is invalid: the wall would close the arena"),
        (["env.wall_half_length=0.28"], "env.wall_half_length=0.28 is invalid: the wall would close the arena"),
        (["env.wall_half_length=0.27"], "env.wall_half_length=0.27 is invalid: the gaps at the wall's ends would be"),
        (["env.wall_half_length=0.01"], "would not block every start's straight path"),
        (["env.wall_half_thickness=0.2"], "env.wall_half_thickness=0.2 is invalid: out of range"),
        (["env.start_spread=-0.01"], "env.start_spread=-0.01 is invalid: out of range"),
    ],
)
def test_a_bad_option_exits_2_naming_it_and_its_range(argv, message, capsys):
    key = argv[0].split("=")[0]
    assert main(["train", f"task={TASK}", *argv, "--explain", key]) == 2
    err = capsys.readouterr().err
    assert message in err and "expected a number in [" in err and "Traceback" not in err, err
    with pytest.raises(ConfigError, match=key.removeprefix("env.")):
        make_env_cfg(TASK, **{key.removeprefix("env."): float(argv[0].split("=")[1])})


def test_a_bad_mix_exits_2(tmp_path, capsys):
    argv = ["collect", f"task={TASK}", "demonstrator=scripted", "demonstrator.left_share=1.5", "episodes=1"]
    assert main([*argv, f"out={tmp_path / 'data'}"]) == 2
    err = capsys.readouterr().err
    assert "demonstrator.left_share=1.5 is invalid: out of range; expected a number in [0, 1]" in err, err
    assert not (tmp_path / "data").exists()


def test_the_wall_stops_a_mass_driven_straight_at_it(env):
    """Pushed along x with (almost) full force, the mass comes to rest touching the wall (its centre at the face
    -+0.02 minus -+ its radius 0.01), does not pass through, and follows MuJoCo C's trajectory on the same file; one
    beyond the wall's end (|y| > 0.16) passes."""
    starts = [[-0.2, 0.0], [-0.1, 0.12], [0.2, -0.05], [-0.2, 0.2]]
    put(env, starts)
    action = torch.tensor([[PUSH, 0.0], [PUSH, 0.0], [-PUSH, 0.0], [PUSH, 0.0]])[torch.arange(N) % 4]
    model = mujoco.MjModel.from_xml_path(str(env.task.model_path()))
    datas = [mujoco.MjData(model) for _ in starts]
    for data, start in zip(datas, starts):
        data.qpos[:] = start
    worst = 0.0
    for _ in range(150):
        env.step(action)
        for data, a in zip(datas, action[:4]):
            data.ctrl[:] = np.tanh(a.numpy())
            mujoco.mj_step(model, data)
        worst = max(worst, float(np.abs(env.qpos[:4].numpy() - np.stack([d.qpos for d in datas])).max()))
    x = env.qpos[:, 0].reshape(-1, 4)
    np.testing.assert_allclose(x[:, 0].numpy(), -A, atol=1e-4)
    np.testing.assert_allclose(x[:, 1].numpy(), -A, atol=1e-4)
    np.testing.assert_allclose(x[:, 2].numpy(), A, atol=1e-4)
    assert (x[:, 3] > A + 0.03).all()  # passed over the wall's end
    assert worst < 1e-4, f"max |q - MuJoCo C q| {worst:.2e}"
    assert (env.qpos[:4, 1] - torch.tensor([0.0, 0.12, -0.05, 0.2])).abs().max() < 1e-4  # no sideways push


def test_the_options_size_the_wall():
    wide = make_env(TASK, num_envs=2, device="cpu", seed=0, wall_half_length=0.22, wall_half_thickness=0.05)
    np.testing.assert_allclose(wide.task.wall_half_sizes()[:, :2], [[0.05, 0.22]] * 2, rtol=1e-6)
    put(wide, [[-0.2, 0.2], [-0.2, 0.0]])
    for _ in range(150):
        wide.step(torch.tensor([[PUSH, 0.0], [PUSH, 0.0]]))
    np.testing.assert_allclose(wide.qpos[:, 0].numpy(), -0.06, atol=1e-4)  # at y = 0.2 too: the wall is longer
    # the reward's path length grows with the wall: (-0.2, 0) -> corner (-0.06, 0.23) -> (0.06, 0.23) -> target
    put(wide, [[-0.2, 0.0]])
    path = 2 * math.hypot(0.14, 0.23) + 0.12
    assert wide.compute_rewards(torch.zeros(2, 2))[0].item() == pytest.approx(0.5 * (1 - (path - 0.015)), abs=1e-5)


# (position, pre-tanh action, hand-worked reward): (near + progress) / 2 * small_control, near = 0.1^(d^2) at d
# margins of 0.015 beyond the target's radius 0.015 (0 beyond a few margins), progress = 1 - (path - 0.015).
H = math.hypot(0.17, 0.16)  # from a far corner (+-0.03, +-0.16) of the grown wall to the target, and from the start
HAND_WORKED = [
    ((0.2, 0.0), (0.0, 0.0), 1.0),  # on the target
    ((0.2, 0.0), (math.atanh(0.5), -math.atanh(0.5)), 0.95),  # controls +-0.5: small_control (4 + 0.75) / 5
    ((0.2, 0.03), (0.0, 0.0), (0.1 + 0.985) / 2),  # one margin out: near 0.1; path 0.03 in sight
    ((-0.2, 0.0), (0.0, 0.0), (1 - (2 * H + 0.06 - 0.015)) / 2),  # the start: corner, along the wall, corner
    ((-0.2, 0.05), (0.0, 0.0), (1 - (math.hypot(0.17, 0.11) + 0.06 + H - 0.015)) / 2),  # the nearer (left) way
    ((-0.2, -0.05), (0.0, 0.0), (1 - (math.hypot(0.17, 0.11) + 0.06 + H - 0.015)) / 2),  # its mirror: the same
    ((-A, 0.0), (0.0, 0.0), (1 - (0.16 + 0.06 + H - 0.015)) / 2),  # against the wall's middle
    ((-A, 0.08), (0.0, 0.0), (1 - (0.08 + 0.06 + H - 0.015)) / 2),  # against the wall, halfway to its end
    ((0.0, 0.2), (0.0, 0.0), (1 - (math.hypot(0.2, 0.2) - 0.015)) / 2),  # beyond the end: the target in sight
]


def test_rewards_at_hand_chosen_states(env):
    put(env, [c[0] for c in HAND_WORKED])
    actions = torch.tensor([c[1] for c in HAND_WORKED])[torch.arange(N) % len(HAND_WORKED)]
    got = env.compute_rewards(actions)[: len(HAND_WORKED)].numpy()
    np.testing.assert_allclose(got, [c[2] for c in HAND_WORKED], rtol=1e-5, atol=1e-6)
    # Sliding along the wall towards its end moves away from the target (0.23 -> 0.243): a Euclidean distance term
    # would hold the mass against the wall's middle; the path length rewards the slide (see the module docstring).
    assert math.hypot(0.2 + A, 0.08) > 0.2 + A and got[7] > got[6]


def test_rewards_match_the_independent_path_length_everywhere(env):
    """Random positions outside the grown wall (mirrored pairs (x, y), (x, -y)) vs the visibility-graph reference."""
    gen = torch.Generator().manual_seed(0)
    pos = (torch.rand(4 * N, 2, generator=gen) * 2 - 1) * 0.29
    pos = pos[(pos[:, 0].abs() > A) | (pos[:, 1].abs() > B)][: N // 2]
    pos = torch.cat([pos, pos * torch.tensor([1.0, -1.0])])
    env.set_state(pos, torch.zeros(N, 2))
    got = env.compute_rewards(torch.zeros(N, 2)).numpy()
    expected = [(1 - max(wall_path_length(p, (0.2, 0.0), A, B) - 0.015, 0.0)) / 2 for p in pos.numpy()]
    near = np.array([0.1 ** ((max(np.hypot(p[0] - 0.2, p[1]) - 0.015, 0) / 0.015) ** 2) / 2 for p in pos.numpy()])
    np.testing.assert_allclose(got, np.array(expected) + near, atol=2e-6)
    np.testing.assert_array_equal(got[: N // 2], got[N // 2 :])  # the two ways are mirror images


def test_resets_start_at_rest_on_the_axis_before_the_wall(env):
    qpos, qvel = [], []
    for _ in range(4):
        env.reset()
        qpos.append(env.qpos.clone())
        qvel.append(env.joint_qd.clone())
    qpos, qvel = torch.cat(qpos), torch.cat(qvel)
    for values, low, high in ((qpos[:, 0], -0.22, -0.18), (qpos[:, 1], -0.02, 0.02)):
        assert low - 1e-6 <= values.min() and values.max() <= high + 1e-6
        assert values.max() - values.min() > 0.9 * (high - low)
    assert (qvel == 0).all()


def roll(env, policy, steps):
    """Roll ``policy`` from fresh resets; per env: the side of y where it crossed x = 0 (0: never), the final
    distance to the target and the smallest clearance to the grown wall."""
    obs = env.reset()
    side, clearance = torch.zeros(env.num_envs), torch.full((env.num_envs,), math.inf)
    for _ in range(steps):
        obs, _, _, _ = env.step(policy(obs))
        p = obs["policy"][:, :2]
        side = torch.where((side == 0) & (p[:, 0] > 0), torch.sign(p[:, 1]), side)
        gap = torch.stack([(p[:, 0].abs() - A).clamp(min=0), (p[:, 1].abs() - B).clamp(min=0)], dim=-1)
        clearance = torch.minimum(clearance, gap.norm(dim=-1))
    return side, (obs["policy"][:, :2] - TARGET).norm(dim=-1), clearance, obs


def test_the_demonstrator_reaches_the_target_by_both_ways_in_its_mix(env):
    demo = make_demonstrator(make_env_cfg(TASK), torch.Generator().manual_seed(0), left_share=0.6)
    side, distance, clearance, _ = roll(env, demo, 420)  # the target is reached after ~360 steps
    assert torch.equal(side, demo.side)  # every episode went the way drawn at its start
    assert (distance < 0.015).all(), distance.max()  # inside the target: every episode, by either way
    assert (clearance > 0.003).all(), clearance.min()  # around the wall without touching it
    left = int((side > 0).sum())
    assert 0 < left < N and binomtest(left, N, 0.6).pvalue > 1e-3, left


def test_the_mean_of_the_two_ways_ends_against_the_wall(env):
    """From where the ways part (a reset state), the left and right ways' actions have opposite y and equal x
    components; their mean, rolled out, drives the mass into the wall's middle and keeps it there."""
    demo = make_demonstrator(make_env_cfg(TASK), torch.Generator().manual_seed(0))
    start = torch.tensor([[-0.2, 0.0, 0.0, 0.0]])
    left, right = demo.actions(start, torch.ones(1)), demo.actions(start, -torch.ones(1))
    assert left[0, 0] == right[0, 0] > 0 and left[0, 1] == -right[0, 1] > 0
    _, distance, _, obs = roll(env, lambda o: demo.mean_of_ways(o["policy"]), 300)
    p = obs["policy"][:, :2]
    np.testing.assert_allclose(p[:, 0].numpy(), -A, atol=1e-4)  # at rest against the wall
    assert p[:, 1].abs().max() < 0.03 and (distance > 0.22).all()  # in the middle, far from the target


def test_collect_writes_a_dataset_of_the_demonstrator(tmp_path):
    import minari

    summary = collect(
        {
            "task": TASK,
            "demonstrator": "scripted",
            "demonstrator.left_share": 0.6,
            "episodes": 2,
            "num_envs": 2,
            "out": str(tmp_path / "data"),
        }
    )
    assert summary["episodes"] == 2 and summary["steps"] == 2000 and summary["return_mean"] > 700
    data = minari.MinariDataset(str(tmp_path / "data"))
    assert data.total_episodes == 2
    for episode in data.iterate_episodes():
        assert episode.actions.shape == (1000, 2)
        assert np.abs(episode.actions).max() == pytest.approx(math.atanh(0.99), rel=1e-4)  # the demonstrator's bound
        assert np.linalg.norm(episode.observations[-1, :2] - [0.2, 0.0]) < 0.015


def test_episode_metrics_say_the_way_and_the_success_the_trajectory_shows():
    """At each episode's end the env reports ``success``, ``went_left`` and ``went_right``; they must agree with the
    trajectory read back from the observations: the sign of y where x first passed zero, and the final distance. Half
    the envs follow the demonstrator (both ways, reaching the target), half the mean of its ways (never passing)."""
    env = make_env(TASK, num_envs=16, device="cpu", seed=5)
    demo = make_demonstrator(make_env_cfg(TASK), torch.Generator().manual_seed(1), left_share=0.5)
    averaged = torch.arange(16) >= 8

    def policy(obs):
        return torch.where(averaged[:, None], demo.mean_of_ways(obs["policy"]), demo(obs))

    obs = env.reset()
    side = torch.zeros(16)
    for _ in range(env.max_episode_length - 1):
        obs, _, dones, extras = env.step(policy(obs))
        assert not dones.any()
        p = obs["policy"][:, :2]
        side = torch.where((side == 0) & (p[:, 0] > 0), torch.sign(p[:, 1]), side)
    final = obs["policy"][:, :2]  # the last step moves a mass at rest in the target by far less than its radius
    _, _, dones, extras = env.step(policy(obs))
    assert dones.all()
    log = extras["log"]
    torch.testing.assert_close(log["Episode/went_left"], (side > 0).float())
    torch.testing.assert_close(log["Episode/went_right"], (side < 0).float())
    torch.testing.assert_close(log["Episode/success"], ((final - TARGET).norm(dim=-1) <= 0.015).float())
    assert (side[~averaged] != 0).all() and (side[averaged] == 0).all()  # the check sees passes and non-passes
    assert 0 < int((side > 0).sum()) < 8 and log["Episode/success"][~averaged].all()
    # The next episodes start with the way forgotten: after one step from the reset no env has passed yet.
    _, _, _, extras = env.step(policy(env.get_observations()))
    assert not env.episode_metric_buffers["went_left"].any() and not env.episode_metric_buffers["went_right"].any()


def test_a_run_logs_the_ways_through_training_and_in_eval_json(tmp_path):
    """The task's episode metrics reach the periodic evaluation's curves (``eval/<metric>``) and ``eval.json``."""
    import json

    from refpo_warp.training import train

    out = train(
        [
            f"task={TASK}", "algo=ppo", "device=cpu", "seed=1", "num_envs=4", "runner.num_steps_per_env=8",
            "max_iterations=1", "eval.interval=1", "eval.num_envs=4", "eval.interval_num_envs=4",
            f"run_dir={tmp_path / 'run'}",
        ]
    )  # fmt: skip
    final = out["results"]["mean_action"]
    row = json.loads((tmp_path / "run" / "progress.jsonl").read_text().splitlines()[-1])
    for metric in ("success", "went_left", "went_right"):
        assert f"eval/{metric}" in row and f"{metric}_mean" in final
        assert final[f"{metric}_mean"] in (0.0, 0.25, 0.5, 0.75, 1.0)  # a share of 4 episodes
    assert final["went_left_mean"] + final["went_right_mean"] <= 1.0
