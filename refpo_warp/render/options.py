"""The options of a recorded video, one home for their defaults and rules (Warp-free: a config resolves without a
simulator). ``refpo play`` takes them as ``key=value``; a training run takes them as ``video.<key>``, with
``video.at_end`` and ``video.interval`` saying when it records."""

from __future__ import annotations

from dataclasses import dataclass, fields

from refpo_warp.models.sampled_policy import NUM_FLOW_STEPS
from refpo_warp.utils.errors import unknown
from refpo_warp.utils.option_rules import Flag, Int, ListOf, OneOf, Real, Text, check_options

VIDEO_FORMATS = ("mp4", "gif", "both")


@dataclass
class VideoOptions:
    flow_steps: list[int] | None = None
    """One panel per flow-step count N, side by side from the same initial states (flow policies; None: the policy's
    own N, or the first of ``eval.flow_steps`` in a run)."""
    num_envs: int = 1
    """Envs shown in each panel, tiled."""
    length: int | None = None
    """Env steps recorded; None: until every shown env ends its first episode (at most its time-out)."""
    width: int = 640
    height: int = 480
    camera: str = "default"
    """``default`` (the task's: a tracking camera for cheetah, walker and the humanoid, a fixed one elsewhere),
    ``track``, ``fixed`` or a camera of the model file."""
    format: str = "mp4"
    fps: float | None = None
    """Frames per second of the file, played in real time (every k-th env step drawn); None: at most 30."""
    shadows: bool = False
    """Shadows cost a software renderer several times the frame time."""
    reference: bool = True
    """The humanoid's reference motion beside the simulated body."""
    seed: int | None = None
    """Seed of the envs' initial states and the policy's noise; None: the run's seed (0 without a run)."""
    name: str | None = None
    """File name without suffix; None: from the checkpoint, the flow steps and the agent."""
    at_end: bool = False
    """Training: record the final evaluation's policy into ``<run dir>/videos/``."""
    interval: int = 0
    """Training: also record at every k-th periodic evaluation (0: only at the end, if ``at_end``)."""

    option_rules = {
        "flow_steps": ListOf(NUM_FLOW_STEPS, min_len=1, max_len=4, optional=True),
        "num_envs": Int(1, 64),
        "length": Int(1, 100_000, optional=True),
        "width": Int(16, 4096, multiple_of=2),
        "height": Int(16, 4096, multiple_of=2),
        "camera": Text(),
        "format": OneOf(VIDEO_FORMATS),
        "fps": Real(1, 240, optional=True),
        "shadows": Flag(),
        "reference": Flag(),
        "seed": Int(0, 2**32 - 1, optional=True),
        "name": Text(optional=True),
        "at_end": Flag(),
        "interval": Int(0, 10**8),
    }

    def __post_init__(self) -> None:
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        for name, value in check_options(self.option_rules, values, "video.").items():
            setattr(self, name, value)

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
