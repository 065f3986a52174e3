"""The options of a recorded video, each a field with its default, rule and doc (``refpo_warp/utils/options.py``;
Warp-free: a config resolves without a simulator). ``refpo play`` takes them as ``key=value``; a training run takes
them as ``video.<key>``, with ``video.at_end`` and ``video.interval`` saying when it records."""

from __future__ import annotations

from dataclasses import dataclass, fields

from refpo_warp.models.sampled_policy import NUM_FLOW_STEPS
from refpo_warp.utils.errors import unknown
from refpo_warp.utils.option_rules import Flag, Int, ListOf, OneOf, Real, Text
from refpo_warp.utils.options import check_fields, option

VIDEO_FORMATS = ("mp4", "gif", "both")


@dataclass
class VideoOptions:
    flow_steps: list[int] | None = option(
        None,
        ListOf(NUM_FLOW_STEPS, min_len=1, max_len=4, optional=True),
        "one panel per flow-step count N, side by side from the same initial states (flow policies; null: the "
        "policy's own N, or the first of eval.flow_steps in a run)",
    )
    num_envs: int = option(1, Int(1, 64), "envs shown in each panel, tiled")
    length: int | None = option(
        None,
        Int(1, 100_000, optional=True),
        "env steps recorded; null: until every shown env ends its first episode (at most its time-out)",
    )
    width: int = option(640, Int(16, 4096, multiple_of=2), "frame width in pixels")
    height: int = option(480, Int(16, 4096, multiple_of=2), "frame height in pixels")
    camera: str = option(
        "default",
        Text(),
        "default (the task's: a tracking camera for cheetah, walker and the humanoid, a fixed one elsewhere), track, "
        "fixed or a camera of the model file",
    )
    format: str = option("mp4", OneOf(VIDEO_FORMATS), "mp4, gif or both")
    fps: float | None = option(
        None,
        Real(1, 240, optional=True),
        "frames per second of the file, played in real time (every k-th env step drawn); null: at most 30",
    )
    shadows: bool = option(False, Flag(), "shadows (they cost a software renderer several times the frame time)")
    reference: bool = option(True, Flag(), "the humanoid's reference motion beside the simulated body")
    seed: int | None = option(
        None,
        Int(0, 2**32 - 1, optional=True),
        "seed of the envs' initial states and the policy's noise; null: the run's seed (0 without a run)",
    )
    name: str | None = option(
        None, Text(optional=True), "file name without suffix; null: from the checkpoint, the flow steps and the agent"
    )
    at_end: bool = option(False, Flag(), "training: record the final evaluation's policy into <run dir>/videos/")
    interval: int = option(
        0, Int(0, 10**8), "training: also record at every k-th periodic evaluation (0: only at the end, if at_end)"
    )

    def __post_init__(self) -> None:
        check_fields(self, "video.")

    @classmethod
    def from_dict(cls, values: dict, prefix: str = "video.") -> VideoOptions:
        """Options from a ``{key: value}`` mapping; an unknown key names the closest valid one."""
        valid = [f.name for f in fields(cls)]
        for key in values:
            if key not in valid:
                raise unknown("video option", f"{prefix}{key}", [f"{prefix}{k}" for k in valid])
        return cls(**values)

    def formats(self) -> tuple[str, ...]:
        return ("mp4", "gif") if self.format == "both" else (self.format,)
