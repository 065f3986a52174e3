"""Synthetic clips checked by forward kinematics: walking speed and turning rate as specified, no sliding of a
foot on the ground, feet on (never below) the ground, plausible pelvis/head heights; the shipped default set is
what the tool generates, and it loads."""

from __future__ import annotations

import numpy as np
import pytest

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion import rotations as rot
from refpo_warp.motion.amass import read_amass
from refpo_warp.motion.clip import FOOT_INDICES
from refpo_warp.motion.skeleton import BODY_NAMES, FOOT_SOLE_DEPTH
from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, generate_motion, random_clip_specs
from refpo_warp.utils.paths import REPO_ROOT

REPO = REPO_ROOT
SHIPPED = REPO / "tasks" / "humanoid" / "data" / "synthetic"
HEAD, PELVIS = BODY_NAMES.index("Head"), 0


def fk(spec):
    root_pos, root_rot, local = generate_motion(spec)
    pos, quat = kin.forward_kinematics(root_pos, root_rot, local)
    soles = pos[:, FOOT_INDICES].copy()
    soles[..., 2] -= FOOT_SOLE_DEPTH
    return pos, quat, soles


@pytest.mark.parametrize("spec", DEFAULT_CLIP_SPECS, ids=lambda s: s.name)
def test_clip_is_grounded_and_plausible(spec):
    pos, _, soles = fk(spec)
    lowest = soles[..., 2].min(axis=1)
    assert lowest.min() > -1e-9  # no foot point below the ground
    if spec.kind in ("walk", "turn"):
        np.testing.assert_allclose(lowest, 0.0, atol=1e-9)  # a foot is always on the ground
        assert pos[:, PELVIS, 2].min() > 0.82 and pos[:, PELVIS, 2].max() < 0.93
        assert soles[..., 2].max() > 0.05  # swinging feet clear the ground
    else:
        np.testing.assert_allclose(lowest, 0.0, atol=2e-3)
        np.testing.assert_allclose(pos[:, PELVIS, 2], 0.934, atol=3e-3)  # standing with soft knees
    assert pos[:, HEAD, 2].min() > 1.40 and pos[:, HEAD, 2].max() < 1.52
    # Contact points do not slide: between consecutive frames on the ground, a sole point stays put.
    on_ground = soles[..., 2] < 1e-4
    both = on_ground[1:] & on_ground[:-1]
    slide = np.linalg.norm(np.diff(soles[..., :2], axis=0), axis=-1) * spec.fps
    assert both.sum() > 0.3 * both.size and slide[both].max() < 0.02


@pytest.mark.parametrize("spec", [s for s in DEFAULT_CLIP_SPECS if s.kind in ("walk", "turn")], ids=lambda s: s.name)
def test_walk_speed_and_heading(spec):
    pos, quat, _ = fk(spec)
    cycles = int(spec.duration * spec.gait_freq)  # compare over whole strides (the pelvis sways within one)
    n = int(round(cycles / spec.gait_freq * spec.fps))
    facing = rot.quat_rotate(quat[:, PELVIS], np.array([1.0, 0.0, 0.0]))
    yaw = np.unwrap(np.arctan2(facing[:, 1], facing[:, 0]))
    np.testing.assert_allclose(yaw[n] - yaw[0], spec.turn_rate * n / spec.fps * (spec.kind == "turn"), atol=0.02)
    chord = np.linalg.norm(pos[n, PELVIS, :2] - pos[0, PELVIS, :2])
    angle = abs(spec.turn_rate) * n / spec.fps if spec.kind == "turn" else 0.0
    arc = chord * angle / (2 * np.sin(angle / 2)) if angle > 0 else chord
    np.testing.assert_allclose(arc / (n / spec.fps), spec.speed, rtol=0.02)
    # The pelvis starts facing the clip's heading (up to its small sway with the legs).
    assert abs(rot.wrap_angle(yaw[0] - spec.heading)) < 0.1


def test_wave_raises_the_hand_above_the_head():
    wave = next(s for s in DEFAULT_CLIP_SPECS if s.name == "wave_right")
    pos, _, _ = fk(wave)
    hand = pos[:, BODY_NAMES.index("R_Hand"), 2]
    assert hand[: int(0.1 * wave.fps)].max() < 1.0 and hand[-int(wave.fps) :].min() > pos[-1, HEAD, 2]
    other = pos[:, BODY_NAMES.index("L_Hand"), 2]
    assert other.max() < 1.0  # the other arm hangs


def test_random_specs_are_reproducible_and_valid():
    specs = random_clip_specs(8, seed=5)
    assert specs == random_clip_specs(8, seed=5) and specs != random_clip_specs(8, seed=6)
    for spec in specs:
        _, _, soles = fk(spec)
        assert soles[..., 2].min() > -1e-9


def test_shipped_default_set_is_the_generated_one():
    files = sorted(SHIPPED.glob("*_poses.npz"))
    assert [f.name for f in files] == sorted(f"{s.name}_poses.npz" for s in DEFAULT_CLIP_SPECS)
    assert sum(f.stat().st_size for f in files) < 2 * 2**20
    assert {read_amass(f).fps for f in files} == {30.0, 60.0, 100.0, 120.0}
    for spec in DEFAULT_CLIP_SPECS:
        motion, want = read_amass(SHIPPED / f"{spec.name}_poses.npz"), generate_amass(spec)
        np.testing.assert_allclose(motion.body_pose, want["body_pose"], atol=1e-9)
        np.testing.assert_allclose(motion.trans, want["trans"], atol=1e-9)


def test_make_clips_command(tmp_path, capsys):
    from refpo_warp.cli.main import main

    out = str(tmp_path / "x")
    assert main(["make-clips", f"out={out}", "random=3", "seed=1", "schema=smplx", "fps=50"]) == 0
    files = sorted((tmp_path / "x").glob("*_stageii.npz"))
    assert len(files) == 3 and all(read_amass(f).schema == "smplx" and read_amass(f).fps == 50 for f in files)
    assert "wrote 3 clips" in capsys.readouterr().out
