"""AMASS reader: round trips through both schemas at several frame rates, resampling by time, and an error that
names the file and the problem for every kind of bad input."""

from __future__ import annotations

import numpy as np
import pytest

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion import rotations as rot
from refpo_warp.motion.amass import read_amass, write_amass
from refpo_warp.motion.clip import build_clip, resample
from refpo_warp.motion.sources import find_amass_files, load_amass_clips
from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, with_fps
from refpo_warp.utils.errors import MotionDataError

WALK = DEFAULT_CLIP_SPECS[1]  # walk_normal
WAVE = DEFAULT_CLIP_SPECS[9]  # wave_right


def write_clip(path, spec, schema="smplh", dtype=np.float64):
    clip = generate_amass(spec)
    return write_amass(path, clip["root_orient"], clip["body_pose"], clip["trans"], clip["fps"], schema, dtype=dtype)


@pytest.mark.parametrize("schema", ["smplh", "smplx"])
@pytest.mark.parametrize("fps", [30, 60, 100, 120])
def test_round_trip_both_schemas(tmp_path, schema, fps):
    spec = with_fps(WALK, fps)
    want = generate_amass(spec)
    path = write_clip(tmp_path / f"clip_{schema}.npz", spec, schema)
    with np.load(path) as data:  # the files carry the published keys and shapes
        if schema == "smplh":
            assert data["poses"].shape == (want["trans"].shape[0], 156) and "mocap_framerate" in data.files
            assert data["dmpls"].shape[1] == 8 and not np.any(data["poses"][:, 66:])
        else:
            assert data["poses"].shape[1] == 165 and data["pose_hand"].shape[1] == 90
            assert float(data["mocap_frame_rate"]) == fps
    motion = read_amass(path)
    assert motion.schema == schema and motion.fps == fps
    np.testing.assert_array_equal(motion.root_orient, want["root_orient"])
    np.testing.assert_array_equal(motion.body_pose, want["body_pose"])
    np.testing.assert_array_equal(motion.trans, want["trans"])
    # Converted at its own rate, the clip reproduces the generator's model-frame motion (already grounded).
    clips, _ = load_amass_clips(path, float(fps))
    root_pos, root_rot, local = kin.amass_to_model(want["root_orient"], want["body_pose"], want["trans"])
    body_pos, _ = kin.forward_kinematics(root_pos, root_rot, local)
    np.testing.assert_allclose(clips[0].body_pos, body_pos, atol=1e-9)


def test_float32_files_read_back(tmp_path):
    path = write_clip(tmp_path / "f32_poses.npz", WAVE, dtype=np.float32)
    motion = read_amass(path)
    np.testing.assert_allclose(motion.body_pose, generate_amass(WAVE)["body_pose"], atol=1e-6)


def test_same_motion_at_any_source_rate_resamples_to_the_same_frames(tmp_path):
    """A motion generated at 60/100/120 fps (times k/fps of one smooth function) gives one 30 fps clip."""
    clips = {}
    for fps in (30, 60, 100, 120):
        path = write_clip(tmp_path / f"walk{fps}_poses.npz", with_fps(WALK, fps))
        clips[fps] = load_amass_clips(path, 30.0)[0][0]
    assert {c.num_frames for c in clips.values()} == {int(WALK.duration * 30) + 1}
    for fps in (60, 100, 120):
        # 100 fps frames miss most 30 fps times: the slerp/lerp interpolation error stays within millimetres.
        np.testing.assert_allclose(clips[fps].body_pos, clips[30].body_pos, atol=4e-3)
        np.testing.assert_allclose(clips[fps].dof_pos, clips[30].dof_pos, atol=2e-2)


def test_resample_is_exact_for_motion_linear_in_time():
    # Root moving at constant velocity and a joint turning at a constant rate about a fixed axis: lerp/slerp are
    # exact at any in-between time, so 120 fps resampled to 30 fps equals the motion sampled at 30 fps directly.
    def motion(t):
        root = np.stack([0.5 * t, -0.2 * t, 0.9 + 0.01 * t], axis=1)
        spin = rot.quat_from_axis_angle(np.outer(1.7 * t, [0.6, 0.0, 0.8]))
        local = np.repeat(spin[:, None], 24, axis=1)
        return root, spin, local

    src = motion(np.arange(0, 361) / 120.0)
    out = resample(*src, src_fps=120.0, fps=30.0)
    want = motion(np.arange(0, 91) / 30.0)
    np.testing.assert_allclose(out[0], want[0], atol=1e-12)
    assert np.allclose(np.abs(np.sum(out[1] * want[1], -1)), 1.0, atol=1e-12)
    assert np.allclose(np.abs(np.sum(out[2] * want[2], -1)), 1.0, atol=1e-12)
    # Non-divisible rates: 100 fps over 1.005 s ends at the last 30 fps time inside the clip (1.0 s).
    out = resample(*motion(np.arange(0, 101) / 100.0), src_fps=100.0, fps=30.0)
    assert out[0].shape[0] == 31
    np.testing.assert_allclose(out[0], motion(np.arange(0, 31) / 30.0)[0], atol=1e-12)


def test_ground_fix_uses_the_clip_start():
    # Rest pose lifted by 0.3 m for the first second, then stepping 0.2 m down (a staircase): the clip start
    # decides the ground, so the lowest sole is at z = 0 in the first second and below it afterwards.
    t = np.arange(0, 61) / 30.0
    root_pos = np.stack([t, 0 * t, 1.3 - 0.2 * (t > 1.5)], axis=1)
    local = rot.quat_identity((t.size, 24))
    clip = build_clip("stairs", root_pos, rot.quat_identity((t.size,)), local, 30.0, 30.0)
    from refpo_warp.motion.clip import sole_heights

    soles = sole_heights(clip.body_pos)
    np.testing.assert_allclose(soles[:45], 0.0, atol=1e-12)
    np.testing.assert_allclose(soles[46:], -0.2, atol=1e-12)


# ------------------------------------------------------------------------------------------------- bad input
def write_npz(path, **arrays):
    with open(path, "wb") as f:
        np.savez(f, **arrays)
    return path


def good_arrays(n=5):
    return {"poses": np.zeros((n, 156)), "trans": np.zeros((n, 3)), "mocap_framerate": np.array(60.0)}


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda a: a.pop("poses"), "missing key 'poses'"),
        (lambda a: a.pop("trans"), "missing key 'trans'"),
        (lambda a: a.pop("mocap_framerate"), "missing frame rate key"),
        (lambda a: a.update(poses=np.zeros((5, 30))), "'poses' has shape (5, 30)"),
        (lambda a: a.update(poses=np.zeros(156)), "'poses' has shape (156,)"),
        (lambda a: a.update(trans=np.zeros((5, 2))), "'trans' has shape (5, 2)"),
        (lambda a: a.update(trans=np.zeros((4, 3))), "frame counts differ"),
        (lambda a: a["poses"].__setitem__((3, 7), np.nan), "'poses' has NaN or infinite values (first at frame 3)"),
        (lambda a: a["trans"].__setitem__((1, 2), np.inf), "'trans' has NaN or infinite values (first at frame 1)"),
        (lambda a: a.update(poses=np.zeros((0, 156)), trans=np.zeros((0, 3))), "zero frames"),
        (lambda a: a.update(mocap_framerate=np.array(0.0)), "must be a positive frame rate"),
        (lambda a: a.update(mocap_framerate=np.array([30.0, 60.0])), "must be one number"),
        (lambda a: a.update(poses=np.full((5, 156), "x")), "'poses' has dtype <U1"),
    ],
)
def test_bad_amass_files_name_file_and_problem(tmp_path, change, message):
    arrays = good_arrays()
    change(arrays)
    path = write_npz(tmp_path / "bad_poses.npz", **arrays)
    with pytest.raises(MotionDataError) as err:
        read_amass(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_smplx_missing_or_misshaped_split_keys(tmp_path):
    base = {"trans": np.zeros((5, 3)), "mocap_frame_rate": np.array(120.0), "root_orient": np.zeros((5, 3))}
    path = write_npz(tmp_path / "x_stageii.npz", **base, pose_body=np.zeros((5, 60)))
    with pytest.raises(MotionDataError, match=r"x_stageii.npz: key 'pose_body' has shape \(5, 60\)"):
        read_amass(path)
    path = write_npz(tmp_path / "y_stageii.npz", **base)  # no pose_body and no poses
    with pytest.raises(MotionDataError, match=r"y_stageii.npz: missing key 'poses'.*'root_orient' \+ 'pose_body'"):
        read_amass(path)


def test_not_an_npz(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    with pytest.raises(MotionDataError, match=r"notes.txt: not an .npz file"):
        read_amass(text)
    fake = tmp_path / "fake_poses.npz"
    fake.write_text("this is not a zip archive")
    with pytest.raises(MotionDataError, match=r"fake_poses.npz: cannot be read as an npz archive"):
        read_amass(fake)
    single = tmp_path / "single.npz"
    with open(single, "wb") as f:
        np.save(f, np.zeros(3))  # an .npy payload under an .npz name
    with pytest.raises(MotionDataError, match=r"single.npz: cannot be read as an npz archive"):
        read_amass(single)
    with pytest.raises(MotionDataError, match=r"missing.npz: no such file"):
        read_amass(tmp_path / "missing.npz")


def test_folders(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(MotionDataError, match="empty: no AMASS motion files"):
        find_amass_files(empty)
    # Body-shape files are skipped; motion files in subfolders are found and named by relative path.
    data = tmp_path / "amass"
    write_npz((data / "s1").mkdir(parents=True) or data / "s1" / "shape.npz", betas=np.zeros(16), gender="male")
    write_npz(data / "s1" / "neutral_stagei.npz", betas=np.zeros(16))
    write_clip(data / "s1" / "wave_poses.npz", with_fps(WAVE, 30))
    clips, sources = load_amass_clips(data, 30.0)
    assert [c.name for c in clips] == ["s1/wave_poses"] and sources == [str(data / "s1" / "wave_poses.npz")]
    only_shapes = tmp_path / "shapes"
    only_shapes.mkdir()
    write_npz(only_shapes / "shape.npz", betas=np.zeros(16))
    with pytest.raises(MotionDataError, match="shapes: no AMASS motion files"):
        find_amass_files(only_shapes)
    # One bad file fails the whole folder, naming that file.
    write_npz(data / "s2_poses.npz", **{k: v for k, v in good_arrays().items() if k != "trans"})
    with pytest.raises(MotionDataError, match=r"s2_poses.npz: missing key 'trans'"):
        load_amass_clips(data, 30.0)
