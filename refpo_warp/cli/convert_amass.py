"""``refpo convert-amass``: AMASS motion files into one motion library file."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from refpo_warp.config.command_options import EXPLAIN, command_help, options_or_explain
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Real, Text
from refpo_warp.utils.options import option


@dataclass(frozen=True)
class ConvertOptions:
    out: str = option(rule=Text(), doc="the motion library file written (a name ending in .motionlib.npz)")
    fps: float = option(30.0, Real(1, 1000), "the library frame rate (the control rate)")


SUMMARY = "convert AMASS motion files (a file or a folder) into a motion library file"
USAGE = command_help(
    "Convert AMASS motion files: refpo convert-amass <AMASS .npz file or folder> out=PATH.motionlib.npz [fps=30]",
    """Example: refpo convert-amass ~/data/AMASS/CMU out=runs/cmu.motionlib.npz fps=30

A folder is searched recursively. Every file is validated; the first bad one stops the conversion with a message
naming it (nothing is written). The output is written atomically: an interrupted conversion keeps the previous output
file. The result loads with motion_file=runs/cmu.motionlib.npz (or MotionLibrary.load).""",
    ConvertOptions,
)
FLAGS = (EXPLAIN,)
SUBJECTS = 2  # a second one is refused with the name it has now (out=)


def run(args: Arguments) -> None:
    from refpo_warp.motion.library_file import LIBRARY_SUFFIX

    if len(args.subjects) == 2:
        raise ConfigError("refpo convert-amass: the output file is out=PATH now; see refpo convert-amass --help")
    parsed = options_or_explain("convert-amass", ConvertOptions, args)
    if parsed is None:
        return
    options = parsed[0]
    if len(args.subjects) != 1:
        raise ConfigError(
            "refpo convert-amass takes SOURCE (an AMASS .npz file or a folder of them) and out=PATH; see "
            "refpo convert-amass --help"
        )
    source, output = Path(args.subjects[0]), Path(options.out)
    if not output.name.endswith(LIBRARY_SUFFIX):
        raise ConfigError(f"out= must name a file ending in {LIBRARY_SUFFIX}, got {output.name}")
    convert(source, output, options.fps)


def convert(source: Path, output: Path, fps: float) -> None:
    from refpo_warp.motion.library_file import LIBRARY_SUFFIX
    from refpo_warp.motion.limits import check_fps_argument
    from refpo_warp.motion.motion_library import MotionLibrary

    check_fps_argument(fps, "fps")
    if output.is_dir():
        raise ConfigError(f"out={output} is a directory; give a file name ending in {LIBRARY_SUFFIX}")
    start = time.perf_counter()
    library = MotionLibrary.load(source, device="cpu", fps=fps)
    library.save(output)
    print(f"{library} -> {output} ({output.stat().st_size / 2**20:.1f} MiB, {time.perf_counter() - start:.1f} s)")
