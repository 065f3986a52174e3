"""FlowActor: CFM loss and sampler against hand-worked values; TorchScript and ONNX exports against eager."""

import math

import pytest
import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.models import FlowActor, SinusoidalEmbedding


def make_actor(obs_dim=3, act_dim=2, **kwargs):
    obs = TensorDict({"policy": torch.zeros(4, obs_dim)}, batch_size=[4])
    kwargs.setdefault("hidden_dims", [act_dim])
    return FlowActor(obs, {"actor": ["policy"]}, "actor", act_dim, **kwargs), obs


def identity_flow(**kwargs):
    """An actor whose velocity is exactly v(x, tau; o) = x (linear layers set by hand, identity activation)."""
    actor, obs = make_actor(activation="identity", **kwargs)
    v = actor.velocity
    with torch.no_grad():
        for p in v.parameters():
            p.zero_()
        v.sample_proj.weight[:, :2] = torch.eye(2)  # x part of [x, emb(tau)]
        v.trunk[-1].weight.copy_(torch.eye(2))
    return actor, obs


def test_time_embedding_values():
    emb = SinusoidalEmbedding(4)(torch.tensor([0.5]))
    expected = [math.cos(0.5), math.cos(1.0), math.sin(0.5), math.sin(1.0)]
    torch.testing.assert_close(emb[0], torch.tensor(expected))


def test_cfm_loss_hand_worked_u_and_eps_modes():
    actor, _ = identity_flow()
    obs = TensorDict({"policy": torch.zeros(1, 3)}, batch_size=[1])
    a = torch.tensor([[1.0, -2.0]])
    eps = torch.tensor([[[0.5, 0.5]]])
    tau = torch.tensor([[0.25]])
    # x_tau = 0.75 * (0.5, 0.5) + 0.25 * (1, -2) = (0.625, -0.125); a - eps = (0.5, -2.5)
    # error = ((0.125)^2 + (2.375)^2) / 2 = 2.828125
    assert actor.cfm_loss(obs, a, tau, eps).item() == pytest.approx(2.828125)
    actor.output_mode = "eps"  # weighted by tau^2
    assert actor.cfm_loss(obs, a, tau, eps).item() == pytest.approx(2.828125 * 0.0625)


def test_cfm_loss_is_zero_on_a_straight_field():
    """v(x, tau) = a - eps exactly (constant output) gives zero loss for every tau: the Reflow fixed point."""
    actor, obs = make_actor()
    with torch.no_grad():
        actor.velocity.trunk[-1].weight.zero_()
        actor.velocity.trunk[-1].bias.copy_(torch.tensor([0.3, -0.7]))
    eps = torch.randn(4, 5, 2)
    a = eps[:, 0] + torch.tensor([0.3, -0.7])
    eps = eps[:, :1].expand(4, 5, 2)
    assert actor.cfm_loss(obs, a, torch.rand(4, 5), eps).abs().max() < 1e-6


@pytest.mark.parametrize("steps", [1, 2, 10])
def test_euler_sampler_on_linear_field(steps):
    actor, obs = identity_flow()
    noise = torch.randn(4, 2)
    # dx/dtau = x with Euler step 1/N: x_N = (1 + 1/N)^N x_0
    out = actor.integrate(actor.encode(obs), noise, steps)
    torch.testing.assert_close(out, noise * (1 + 1 / steps) ** steps)


def test_deterministic_output_integrates_from_zero_noise():
    actor, obs = make_actor(hidden_dims=[16, 16])
    torch.testing.assert_close(actor(obs), actor.integrate(actor.encode(obs), torch.zeros(4, 2)))
    assert actor(obs, stochastic_output=True).std(0).sum() > 0


def test_gaussian_ppo_api_is_refused_with_a_clear_message():
    actor, obs = make_actor()
    with pytest.raises(NotImplementedError, match="ReFPO"):
        actor.get_output_log_prob(torch.zeros(4, 2))


@pytest.fixture
def trained_like_actor():
    torch.manual_seed(0)
    actor, obs = make_actor(obs_dim=5, act_dim=3, hidden_dims=[32, 32], obs_normalization=True, num_flow_steps=4)
    actor.update_normalization(TensorDict({"policy": torch.randn(64, 5) * 3 + 1}, batch_size=[64]))
    return actor.eval()


def test_torchscript_export_matches_eager(trained_like_actor):
    actor = trained_like_actor
    scripted = torch.jit.script(actor.as_jit())
    obs = torch.randn(8, 5)
    noise = torch.randn(8, 3)
    eager = actor.integrate(actor.encode(TensorDict({"policy": obs}, batch_size=[8])), noise)
    torch.testing.assert_close(scripted(obs, noise), eager)
    torch.testing.assert_close(scripted(obs), actor(TensorDict({"policy": obs}, batch_size=[8])))


def test_onnx_export_matches_eager(trained_like_actor, tmp_path):
    ort = pytest.importorskip("onnxruntime")
    actor = trained_like_actor
    module = actor.as_onnx().eval()
    path = tmp_path / "policy.onnx"
    torch.onnx.export(module, module.get_dummy_inputs(), str(path), input_names=module.input_names,
                      output_names=module.output_names, opset_version=18, dynamo=False,
                      dynamic_axes={"obs": {0: "batch"}, "noise": {0: "batch"}})  # fmt: skip
    obs, noise = torch.randn(8, 5), torch.randn(8, 3)
    (out,) = ort.InferenceSession(str(path)).run(None, {"obs": obs.numpy(), "noise": noise.numpy()})
    eager = actor.integrate(actor.encode(TensorDict({"policy": obs}, batch_size=[8])), noise)
    torch.testing.assert_close(torch.from_numpy(out), eager, atol=1e-5, rtol=1e-5)


def test_velocity_network_reuses_the_observation_projection():
    """K samples per action share one observation projection (computed once, broadcast)."""
    actor, obs = make_actor(hidden_dims=[8])
    calls = []
    actor.velocity.obs_proj.register_forward_hook(lambda m, i, o: calls.append(o.shape))
    actor.velocity_error(obs, torch.zeros(4, 2), torch.rand(4, 7), torch.randn(4, 7, 2))
    assert calls == [torch.Size([4, 8])]
    assert isinstance(actor.velocity.obs_proj, nn.Linear)
