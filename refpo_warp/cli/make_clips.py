"""``refpo make-clips``: procedural AMASS-format clips (walk, turn, stand with sway, arm waves) into a folder."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from refpo_warp.config.command_options import EXPLAIN, command_help, options_or_explain
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Flag, Int, OneOf, Real, Text
from refpo_warp.utils.options import option

SUFFIX = {"smplh": "_poses.npz", "smplx": "_stageii.npz"}  # AMASS's file naming per schema


@dataclass(frozen=True)
class ClipOptions:
    out: str = option(rule=Text(), doc="the folder the clips are written to")
    random: int = option(0, Int(0, 100_000), "the number of random clips (0: the 12-clip default set)")
    seed: int = option(0, Int(0, 2**32 - 1), "the seed of the random clips")
    schema: str = option("smplh", OneOf(*SUFFIX), "smplh (SMPL+H files) or smplx (SMPL-X stage-ii files)")
    fps: float | None = option(None, Real(1, 1000, optional=True), "every clip's frame rate (null: each clip's own)")
    float32: bool = option(False, Flag(), "store float32 arrays (smaller files)")


SUMMARY = "write procedural AMASS-format clips (the shipped synthetic set, or random variants)"
USAGE = command_help(
    "Write procedural AMASS-format clips (walk, turn, stand with sway, arm waves): refpo make-clips out=DIR "
    "[key=value ...]",
    """Examples:
    refpo make-clips out=OUT_DIR                      # the 12-clip default set (as shipped)
    refpo make-clips out=OUT_DIR random=50 seed=3     # 50 random variants
    refpo make-clips out=OUT_DIR schema=smplx         # SMPL-X stage-ii files instead of SMPL+H

The shipped default set in tasks/humanoid/data/synthetic is this command's default output:
refpo make-clips out=tasks/humanoid/data/synthetic""",
    ClipOptions,
)
FLAGS = (EXPLAIN,)
SUBJECTS = 1  # refused with the name it has now (out=)


def run(args: Arguments) -> None:
    import numpy as np

    from refpo_warp.motion.amass import write_amass
    from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, random_clip_specs, with_fps

    if args.subjects:
        raise ConfigError("refpo make-clips: the output folder is out=DIR now; see refpo make-clips --help")
    parsed = options_or_explain("make-clips", ClipOptions, args)
    if parsed is None:
        return
    options = parsed[0]
    out_dir = Path(options.out)
    specs = random_clip_specs(options.random, options.seed) if options.random > 0 else list(DEFAULT_CLIP_SPECS)
    if options.fps is not None:
        specs = [with_fps(spec, options.fps) for spec in specs]
    dtype = np.float32 if options.float32 else np.float64
    total = 0
    for spec in specs:
        clip = generate_amass(spec)
        path = out_dir / f"{spec.name}{SUFFIX[options.schema]}"
        write_amass(
            path, clip["root_orient"], clip["body_pose"], clip["trans"], clip["fps"], options.schema, dtype=dtype
        )
        total += path.stat().st_size
        print(f"{path}  {spec.kind:5s} {spec.duration:.1f} s at {spec.fps:g} fps")
    print(f"wrote {len(specs)} clips, {total / 1024:.0f} KiB, to {out_dir}")
