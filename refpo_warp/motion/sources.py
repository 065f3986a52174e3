"""Turn a motion source (an AMASS npz file or a folder of them) into library clips, validating every file first."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion.amass import AmassMotion, is_metadata_file, read_amass
from refpo_warp.motion.clip import MotionClip, build_clip
from refpo_warp.motion.library_file import is_library_file
from refpo_warp.motion.limits import MIN_FRAMES, resampled_frame_count
from refpo_warp.utils.errors import MotionDataError


def find_amass_files(folder: Path) -> list[Path]:
    """AMASS motion files under ``folder`` (recursive, sorted), without the body-shape files AMASS ships."""
    if not folder.is_dir():
        raise MotionDataError(f"{folder}: no such folder")
    files = sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() == ".npz")
    libraries = [p for p in files if is_library_file(p)]
    if libraries:
        raise MotionDataError(
            f"{libraries[0]}: a converted motion library inside an AMASS folder; pass the library file itself "
            f"as the motion source, or move it out of {folder}"
        )
    files = [p for p in files if not is_metadata_file(p)]
    if not files:
        raise MotionDataError(f"{folder}: no AMASS motion files (*.npz) found in this folder or below it")
    return files


def clip_from_amass(motion: AmassMotion, name: str, fps: float) -> MotionClip:
    """Convert one AMASS motion to a library clip at ``fps`` (model frame, grounded, with velocities)."""
    if resampled_frame_count(motion.num_frames, motion.fps, fps) < MIN_FRAMES:
        raise MotionDataError(
            f"{motion.path}: too short to resample: {motion.num_frames} frames at {motion.fps:g} fps "
            f"give fewer than {MIN_FRAMES} frames at {fps:g} fps"
        )
    root_pos, root_rot, local_rot = kin.amass_to_model(motion.root_orient, motion.body_pose, motion.trans)
    return build_clip(name, root_pos, root_rot, local_rot, motion.fps, fps)


def load_amass_clips(source: Path, fps: float) -> tuple[list[MotionClip], list[str]]:
    """Clips and their source paths from an AMASS file or folder. A bad file fails the whole load (the caller
    builds nothing from a partial list); files are converted one by one so only the resampled clips stay in
    memory."""
    if source.is_dir():
        files = find_amass_files(source)
        names = [p.relative_to(source).with_suffix("").as_posix() for p in files]
    else:
        files, names = [source], [source.with_suffix("").name]
    clips = [clip_from_amass(read_amass(path), name, fps) for path, name in zip(files, names)]
    return clips, [str(p) for p in files]
