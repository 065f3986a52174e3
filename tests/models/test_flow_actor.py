"""FlowActor: CFM losses and sampler against hand-worked values, its options, and exports against eager."""

import math

import pytest
import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.models import FlowActor
from refpo_warp.models.velocity_field import SinusoidalEmbedding

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)


def make_actor(obs_dim=3, act_dim=2, **kwargs):
    obs = TensorDict({"policy": torch.zeros(4, obs_dim)}, batch_size=[4])
    kwargs.setdefault("hidden_dims", [act_dim])
    return FlowActor(obs, {"actor": ["policy"]}, "actor", act_dim, **kwargs), obs


def identity_flow(**kwargs):
    """An actor whose head outputs exactly x (linear layers set by hand, identity activation)."""
    actor, obs = make_actor(activation="identity", **kwargs)
    v = actor.velocity
    with torch.no_grad():
        for p in v.parameters():
            p.zero_()
        v.sample_proj.weight[:, :2] = torch.eye(2)  # x part of [x, emb(tau)]
        v.head.weight.copy_(torch.eye(2))
    return actor, obs


def constant_head(actor, value):
    with torch.no_grad():
        actor.velocity.head.weight.zero_()
        actor.velocity.head.bias.copy_(torch.tensor(value))


def test_time_embedding_values():
    emb = SinusoidalEmbedding(4)(torch.tensor([0.5]))
    expected = [math.cos(0.5), math.cos(1.0), math.sin(0.5), math.sin(1.0)]
    torch.testing.assert_close(emb[0], torch.tensor(expected))


def test_cfm_loss_hand_worked_in_every_output_mode():
    actor, _ = identity_flow()
    obs = TensorDict({"policy": torch.zeros(1, 3)}, batch_size=[1])
    a = torch.tensor([[1.0, -2.0]])
    eps = torch.tensor([[[0.5, 0.5]]])
    tau = torch.tensor([[0.25]])
    # x_tau = 0.75 * (0.5, 0.5) + 0.25 * (1, -2) = (0.625, -0.125) = v; a - eps = (0.5, -2.5)
    # velocity error ((0.125)^2 + (2.375)^2) / 2 = 2.828125
    assert actor.cfm_loss(obs, a, tau, eps, "u").item() == pytest.approx(2.828125)
    assert actor.cfm_loss(obs, a, tau, eps, "eps").item() == pytest.approx(2.828125 * 0.25**2)
    # clean action x + (1 - tau) v = (0.625, -0.125) * 1.75 -> error vs a: (0.09375, 1.78125): mean sq 1.5908203125
    assert actor.cfm_loss(obs, a, tau, eps, "data").item() == pytest.approx(1.5908203125)
    assert actor.cfm_loss(obs, a, tau, eps, "data").item() == pytest.approx(2.828125 * 0.75**2)
    actor.loss_scale = 200.0
    assert actor.cfm_loss(obs, a, tau, eps, "data").item() == pytest.approx(200 * 1.5908203125)


def test_data_parameterisation_hand_worked():
    """The head predicts the clean action: errors in data space directly, velocity error divided by 1 - tau."""
    actor, obs = make_actor(parameterization="data")
    constant_head(actor, [0.2, -0.4])
    a, eps, tau = torch.tensor([[1.0, 0.0]]), torch.tensor([[[0.5, 0.5]]]), torch.tensor([[0.5]])
    terms = actor.cfm_terms(obs[:1], a, tau, eps)
    assert terms.action_error.item() == pytest.approx((0.8**2 + 0.4**2) / 2)
    assert terms.velocity_error.item() == pytest.approx((0.8**2 + 0.4**2) / 2 / 0.25)
    torch.testing.assert_close(terms.clean_action, torch.tensor([[[0.2, -0.4]]]))


@pytest.mark.parametrize("steps", [1, 2, 10])
def test_data_parameterised_sampler_returns_the_predicted_action(steps):
    """v = (a_hat - x) / (1 - tau): the last Euler step lands exactly on a_hat, for any N and any noise."""
    actor, obs = make_actor(parameterization="data", hidden_dims=[8])
    constant_head(actor, [0.3, -0.1])
    out = actor.sample(obs, steps, initial_noise="random")
    torch.testing.assert_close(out, torch.tensor([[0.3, -0.1]]).expand(4, 2), atol=1e-6, rtol=1e-6)


def test_cfm_loss_is_zero_on_a_straight_field():
    """v(x, tau) = a - eps exactly (constant output) gives zero loss for every tau: the Reflow fixed point."""
    actor, obs = make_actor()
    constant_head(actor, [0.3, -0.7])
    eps = torch.randn(4, 5, 2)
    a = eps[:, 0] + torch.tensor([0.3, -0.7])
    eps = eps[:, :1].expand(4, 5, 2)
    for mode in ("u", "eps", "data"):
        assert actor.cfm_loss(obs, a, torch.rand(4, 5), eps, mode).abs().max() < 1e-6


@pytest.mark.parametrize("steps", [1, 2, 10])
def test_euler_sampler_on_linear_field(steps):
    actor, obs = identity_flow()
    noise = torch.randn(4, 2)
    # dx/dtau = x with Euler step 1/N: x_N = (1 + 1/N)^N x_0
    torch.testing.assert_close(actor.sample(obs, steps, noise=noise), noise * (1 + 1 / steps) ** steps)


def test_noise_and_perturbation_are_separate_flags():
    torch.manual_seed(0)
    actor, _ = make_actor(hidden_dims=[16, 16], action_noise_std=0.05)
    obs = TensorDict({"policy": torch.randn(4000, 3)}, batch_size=[4000])
    zero = actor.sample(obs, initial_noise="zero")
    torch.testing.assert_close(actor(obs), zero)  # rsl_rl's deterministic output: zero noise, no perturbation
    noise = torch.randn(4000, 2)
    clean = actor.sample(obs, noise=noise)
    perturbed = actor.sample(obs, noise=noise, perturbation=True)
    assert (perturbed - clean).std().item() == pytest.approx(0.05, rel=0.05)
    # rsl_rl's rollout sample: random x_0 (not zero), then the perturbation on top of its flow
    rollout = actor(obs, stochastic_output=True)
    x0 = actor._last_noise.clone()
    assert x0.std().item() == pytest.approx(1.0, rel=0.05)
    assert (rollout - actor.sample(obs, noise=x0)).std().item() == pytest.approx(0.05, rel=0.05)


def test_adaln_starts_time_independent_and_head_gain_scales_the_first_actions():
    """Zero-initialised modulation: the prediction ignores tau at first; gain 0.01 makes the first actions small."""
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(2000, 30)}, batch_size=[2000])
    kwargs = {"hidden_dims": [64, 64, 64], "activation": "swish", "time_conditioning": "adaln", "time_embed_dim": 64}
    actor = FlowActor(obs, {"actor": ["policy"]}, "actor", 12, parameterization="data", head_init_gain=0.01, **kwargs)
    feat, x = actor.velocity.project_obs(actor.encode(obs)), torch.randn(2000, 12)
    torch.testing.assert_close(
        actor.velocity.predict(feat, x, torch.full((2000,), 0.1)),
        actor.velocity.predict(feat, x, torch.full((2000,), 0.9)),
    )
    small = actor.sample(obs, 10, "random")
    wide = FlowActor(obs, {"actor": ["policy"]}, "actor", 12, **kwargs).sample(obs, 10, "random")
    assert small.std().item() < 0.06 and small.abs().max().item() < 0.5
    assert wide.std().item() > 10 * small.std().item()


def test_obs_clip_clamps_the_normalised_observation():
    actor, _ = make_actor(obs_clip=2.0)
    obs = TensorDict({"policy": torch.tensor([[5.0, -7.0, 1.0]])}, batch_size=[1])
    torch.testing.assert_close(actor.encode(obs), torch.tensor([[2.0, -2.0, 1.0]]))


def test_gaussian_ppo_api_is_refused_with_a_clear_message():
    actor, _obs = make_actor()
    with pytest.raises(NotImplementedError, match="ReFPO"):
        actor.get_output_log_prob(torch.zeros(4, 2))


@pytest.fixture(
    params=[
        {},
        {
            "parameterization": "data",
            "time_conditioning": "adaln",
            "time_embed_dim": 16,
            "obs_clip": 1.5,
            "head_init_gain": 0.5,
        },
    ],
    ids=["velocity-concat", "data-adaln"],
)
def trained_like_actor(request):
    torch.manual_seed(0)
    actor, _obs = make_actor(
        obs_dim=5, act_dim=3, hidden_dims=[32, 32], obs_normalization=True, num_flow_steps=4, **request.param
    )
    actor.update_normalization(TensorDict({"policy": torch.randn(64, 5) * 3 + 1}, batch_size=[64]))
    return actor.eval()


def test_torchscript_export_matches_eager(trained_like_actor):
    actor = trained_like_actor
    scripted = torch.jit.script(actor.as_jit())
    obs, noise = torch.randn(8, 5), torch.randn(8, 3)
    td = TensorDict({"policy": obs}, batch_size=[8])
    torch.testing.assert_close(scripted(obs), actor(td))  # obs only: the deterministic output
    torch.testing.assert_close(scripted(obs, noise), actor.sample(td, noise=noise))
    one_step = torch.jit.script(actor.as_jit(num_flow_steps=1))
    torch.testing.assert_close(one_step(obs), actor.sample(td, 1, initial_noise="zero"))


def export_onnx(module, path):
    names = module.input_names
    torch.onnx.export(
        module,
        module.get_dummy_inputs(),
        str(path),
        input_names=names,
        output_names=module.output_names,
        opset_version=18,
        dynamo=False,
        dynamic_axes={name: {0: "batch"} for name in names},
    )


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_onnx_export_runs_on_obs_alone_and_matches_torch(trained_like_actor, tmp_path):
    ort = pytest.importorskip("onnxruntime")
    actor = trained_like_actor
    obs = torch.randn(8, 5)
    td = TensorDict({"policy": obs}, batch_size=[8])
    for steps in (1, 4):
        module = actor.as_onnx(num_flow_steps=steps).eval()
        assert module.input_size == 5  # rsl_rl's exporters' name for it; mjlab's tracking export sizes its input so
        export_onnx(module, tmp_path / f"policy_{steps}.onnx")
        session = ort.InferenceSession(str(tmp_path / f"policy_{steps}.onnx"))
        assert [i.name for i in session.get_inputs()] == ["obs"]
        (out,) = session.run(None, {"obs": obs.numpy()})
        expected = actor.sample(td, steps, initial_noise="zero")
        torch.testing.assert_close(torch.from_numpy(out), expected, atol=1e-5, rtol=1e-5)
    module = actor.as_onnx(noise_input=True).eval()
    export_onnx(module, tmp_path / "policy_noise.onnx")
    noise = torch.randn(8, 3)
    (out,) = ort.InferenceSession(str(tmp_path / "policy_noise.onnx")).run(
        None, {"obs": obs.numpy(), "noise": noise.numpy()}
    )
    torch.testing.assert_close(torch.from_numpy(out), actor.sample(td, noise=noise), atol=1e-5, rtol=1e-5)


def test_velocity_network_reuses_the_observation_projection():
    """K samples per action share one observation projection (computed once, broadcast)."""
    actor, obs = make_actor(hidden_dims=[8])
    calls = []
    actor.velocity.obs_proj.register_forward_hook(lambda m, i, o: calls.append(o.shape))
    actor.velocity_error(obs, torch.zeros(4, 2), torch.rand(4, 7), torch.randn(4, 7, 2))
    assert calls == [torch.Size([4, 8])]
    assert isinstance(actor.velocity.obs_proj, nn.Linear)
