"""Per-env random streams of an environment: counter-based ``uint32`` states that task kernels advance in place.

Independent streams (``group_size`` 1): env i draws from ``rand_init(seed, i)``. Group streams (Flow-GRPO's groups,
``EnvCfg.reset_group_size``): envs [g G, (g + 1) G) form group g, and the k-th episode of every member draws from
``rand_init(base of group g, k)``, so all members start their k-th episode from the same state. Tasks draw their
resets (and only their resets) from the stream; after a reset, ``next_episode`` points the env at its next stream.
"""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp


class RandomStreams:
    """The streams of ``num_envs`` envs in the Warp array ``rng`` (shared with the task kernels)."""

    def __init__(self, rng, group_size: int, device) -> None:
        self.rng = rng
        self.group_size = int(group_size)
        self.device = device
        n = rng.shape[0]
        if n % self.group_size:
            raise ValueError(f"env.reset_group_size ({self.group_size}) must divide num_envs ({n})")
        if self.group_size > 1:  # a per-env base seed and episode index
            self._group_base = wp.zeros(n, dtype=wp.int32, device=device)
            self._episode_index = wp.zeros(n, dtype=wp.int32, device=device)

    def reseed(self, seed: int) -> None:
        """Restart every stream from ``seed``."""
        n = self.rng.shape[0]
        if self.group_size > 1:
            wp.launch(
                _seed_group_streams,
                dim=n,
                device=self.device,
                inputs=[seed, self.group_size, self._group_base, self._episode_index, self.rng],
            )
        else:
            wp.launch(_seed_streams, dim=n, inputs=[seed, self.rng], device=self.device)

    def next_episode(self, started) -> None:
        """After the envs in the bool array ``started`` drew their reset: point them at their next episode's stream."""
        if self.group_size > 1:
            wp.launch(
                _next_group_streams,
                dim=self.rng.shape[0],
                device=self.device,
                inputs=[started, self._group_base, self._episode_index, self.rng],
            )


@wp.kernel
def _seed_streams(seed: int, rng: wp.array(dtype=wp.uint32)):
    i = wp.tid()
    rng[i] = wp.rand_init(seed, i)


@wp.kernel
def _seed_group_streams(
    seed: int,
    group_size: int,
    base: wp.array(dtype=wp.int32),
    episode: wp.array(dtype=wp.int32),
    rng: wp.array(dtype=wp.uint32),
):
    i = wp.tid()
    base[i] = wp.int32(wp.rand_init(seed, i // group_size))
    episode[i] = 0
    rng[i] = wp.rand_init(base[i], 0)


@wp.kernel
def _next_group_streams(
    started: wp.array(dtype=wp.bool),
    base: wp.array(dtype=wp.int32),
    episode: wp.array(dtype=wp.int32),
    rng: wp.array(dtype=wp.uint32),
):
    i = wp.tid()
    if started[i]:
        episode[i] = episode[i] + 1
        rng[i] = wp.rand_init(base[i], episode[i])
