"""``refpo make-clips``: procedural AMASS-format clips (walk, turn, stand with sway, arm waves) into a folder."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.utils.command_line import Arguments, Flag
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "write procedural AMASS-format clips (the shipped synthetic set, or random variants)"
USAGE = """Write procedural AMASS-format clips (walk, turn, stand with sway, arm waves) into a folder:

    refpo make-clips OUT_DIR                      # the 12-clip default set (as shipped)
    refpo make-clips OUT_DIR --random 50 --seed 3 # 50 random variants
    refpo make-clips OUT_DIR --schema smplx       # SMPL-X stage-ii files instead of SMPL+H

Flags: --random N (N random clips instead of the default set), --seed K, --schema smplh|smplx, --fps F (every clip's
frame rate), --float32 (smaller files). The shipped default set in tasks/humanoid/data/synthetic is this command's
default output: refpo make-clips tasks/humanoid/data/synthetic
"""
FLAGS = (
    Flag("--schema", str, "smplh or smplx"),
    Flag("--random", int, "the number of random clips"),
    Flag("--seed", int, "the seed of the random clips"),
    Flag("--fps", float, "every clip's frame rate"),
    Flag("--float32", doc="store float32 arrays"),
)
SUBJECTS = 1
SUFFIX = {"smplh": "_poses.npz", "smplx": "_stageii.npz"}  # AMASS's file naming per schema


def run(args: Arguments) -> None:
    import numpy as np

    from refpo_warp.motion.amass import write_amass
    from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, random_clip_specs, with_fps

    if not args.subjects or args.options:
        raise ConfigError("refpo make-clips takes OUT_DIR and flags; see refpo make-clips --help")
    out_dir, schema = Path(args.subjects[0]), args.flag("--schema", "smplh")
    if schema not in SUFFIX:
        raise unknown("--schema", schema, SUFFIX)
    count = args.flag("--random", 0)
    specs = random_clip_specs(count, args.flag("--seed", 0)) if count > 0 else list(DEFAULT_CLIP_SPECS)
    if args.flag("--fps") is not None:
        specs = [with_fps(spec, args.flag("--fps")) for spec in specs]
    dtype = np.float32 if args.flag("--float32") else np.float64
    total = 0
    for spec in specs:
        clip = generate_amass(spec)
        path = out_dir / f"{spec.name}{SUFFIX[schema]}"
        write_amass(path, clip["root_orient"], clip["body_pose"], clip["trans"], clip["fps"], schema, dtype=dtype)
        total += path.stat().st_size
        print(f"{path}  {spec.kind:5s} {spec.duration:.1f} s at {spec.fps:g} fps")
    print(f"wrote {len(specs)} clips, {total / 1024:.0f} KiB, to {out_dir}")
