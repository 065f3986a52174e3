"""PhcMLPModel: rsl_rl's ``MLPModel`` with two options of the Puffer-PHC networks (its Gaussian actor and critics).

- ``head_init_gain``: the output head (the mean, for a Gaussian actor) starts orthogonal with this gain and zero bias
  (Puffer-PHC: 0.01, so a Gaussian actor's first actions are its fixed std's noise around ~0);
- ``obs_clip``: the normalised observation is clamped to [-obs_clip, obs_clip] (Puffer-PHC's RunningNorm: 10).
Everything else, the distribution included (``distribution_cfg``, e.g. a fixed std with ``learn_std: false``), and
the JIT/ONNX exports are rsl_rl's.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from rsl_rl.models import MLPModel
from torch import nn

from refpo_warp.models.normalization import with_clip
from refpo_warp.utils.option_rules import Real
from refpo_warp.utils.options import option, option_values
from refpo_warp.utils.rsl_rl_versions import split_learn_std


class PhcMLPModel(MLPModel):
    """``MLPModel`` plus ``head_init_gain`` and ``obs_clip`` (see the module docstring); every other argument is
    ``MLPModel``'s."""

    @dataclass(frozen=True)
    class Options:
        """The options it adds to ``MLPModel``'s arguments."""

        head_init_gain: float | None = option(
            None,
            Real(0, 1e3, lo_open=True, optional=True),
            "orthogonal init of the output head with this gain, zero bias (Puffer-PHC: 0.01); null keeps rsl_rl's",
        )
        obs_clip: float | None = option(
            None,
            Real(0, 1e6, lo_open=True, optional=True),
            "clamp the normalised observation to [-obs_clip, obs_clip] (Puffer-PHC: 10); null: no clamp",
        )

    def __init__(self, *args, **kwargs) -> None:
        options, kwargs = option_values(type(self), kwargs)  # every argument checked against its rule
        o = self.Options(**options)
        head_init_gain, obs_clip = o.head_init_gain, o.obs_clip
        kwargs["distribution_cfg"], learn_std = split_learn_std(kwargs.get("distribution_cfg"))
        super().__init__(*args, **kwargs)
        if not learn_std:  # rsl-rl-lib < 5.2: its GaussianDistribution has no learn_std, so fix the std here
            self.distribution.requires_grad_(False)
        self.obs_normalizer: nn.Module = with_clip(self.obs_normalizer, obs_clip)
        if head_init_gain is not None:
            head = [m for m in self.mlp.modules() if isinstance(m, nn.Linear)][-1]
            rows = self.distribution.output_dim if self.distribution is not None else head.out_features
            with torch.no_grad():
                nn.init.orthogonal_(head.weight[:rows], gain=float(head_init_gain))
                head.bias[:rows].zero_()
