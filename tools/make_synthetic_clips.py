"""Write procedural AMASS-format clips (walk, turn, stand with sway, arm waves) into a folder.

    python tools/make_synthetic_clips.py OUT_DIR                      # the 12-clip default set (as shipped)
    python tools/make_synthetic_clips.py OUT_DIR --random 50 --seed 3 # 50 random variants
    python tools/make_synthetic_clips.py OUT_DIR --schema smplx       # SMPL-X stage-ii files instead of SMPL+H

The shipped default set in tasks/humanoid/data/synthetic is this tool's default output:
    python tools/make_synthetic_clips.py tasks/humanoid/data/synthetic
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from refpo_warp.motion.amass import write_amass
from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, random_clip_specs, with_fps

_SUFFIX = {"smplh": "_poses.npz", "smplx": "_stageii.npz"}  # AMASS's file naming per schema


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out_dir", type=Path)
    parser.add_argument("--schema", choices=sorted(_SUFFIX), default="smplh")
    parser.add_argument("--random", type=int, default=0, metavar="N", help="N random clips instead of the default set")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fps", type=float, default=None, help="override every clip's frame rate")
    parser.add_argument("--float32", action="store_true", help="store float32 arrays (smaller files)")
    args = parser.parse_args(argv)

    specs = random_clip_specs(args.random, args.seed) if args.random > 0 else list(DEFAULT_CLIP_SPECS)
    if args.fps is not None:
        specs = [with_fps(spec, args.fps) for spec in specs]
    dtype = np.float32 if args.float32 else np.float64
    total = 0
    for spec in specs:
        clip = generate_amass(spec)
        path = args.out_dir / f"{spec.name}{_SUFFIX[args.schema]}"
        write_amass(path, clip["root_orient"], clip["body_pose"], clip["trans"], clip["fps"], args.schema, dtype=dtype)
        total += path.stat().st_size
        print(f"{path}  {spec.kind:5s} {spec.duration:.1f} s at {spec.fps:g} fps")
    print(f"wrote {len(specs)} clips, {total / 1024:.0f} KiB, to {args.out_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
