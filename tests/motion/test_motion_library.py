"""The Warp motion library: the sampling kernel against numpy interpolation, the library file round trip and its
validation, and the whole chain against MuJoCo (the library's root pose + hinge angles reproduce its body
positions, rotations and velocities)."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
from test_motion_kinematics import skeleton_mjcf  # (tests/ is on sys.path under pytest)

from refpo_warp.motion import rotations as rot
from refpo_warp.motion.amass import write_amass
from refpo_warp.motion.clip import MotionClip
from refpo_warp.motion.motion_library import MotionLibrary
from refpo_warp.motion.skeleton import BODY_NAMES
from refpo_warp.motion.synthetic import DEFAULT_CLIP_SPECS, generate_amass, with_fps
from refpo_warp.utils.errors import MotionDataError
from refpo_warp.utils.warp_setup import wp

SPECS = {s.name: s for s in DEFAULT_CLIP_SPECS}


@pytest.fixture(scope="module")
def amass_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("amass")
    for name in ("walk_fast", "turn_left", "wave_both"):
        clip = generate_amass(SPECS[name])
        write_amass(folder / f"{name}_poses.npz", clip["root_orient"], clip["body_pose"], clip["trans"], clip["fps"])
    return folder


@pytest.fixture(scope="module")
def library(amass_dir):
    return MotionLibrary.load(amass_dir, device="cpu", fps=30.0)


def reference_sample(lib: MotionLibrary, clip: int, time: float) -> dict[str, np.ndarray]:
    frames = lib.clip(clip)
    f = np.clip(time * lib.fps, 0.0, lib.clip_num_frames[clip] - 1)
    k0 = int(np.floor(f))
    k1, a = min(k0 + 1, lib.clip_num_frames[clip] - 1), f - np.floor(f)
    out = {k: (1 - a) * frames[k][k0] + a * frames[k][k1] for k in ("body_pos", "body_vel", "body_angvel", "dof_vel")}
    q0, q1 = frames["body_rot"][k0].astype(np.float64), frames["body_rot"][k1].astype(np.float64)
    out["body_rot"] = rot.quat_slerp(q0, q1, a)
    d0, d1 = frames["dof_pos"][k0].astype(np.float64), frames["dof_pos"][k1].astype(np.float64)
    out["dof_pos"] = rot.wrap_angle(d0 + a * rot.wrap_angle(d1 - d0))
    return out


def test_library_shapes(library):
    assert library.num_clips == 3 and library.fps == 30.0
    assert library.clip_names == ["turn_left_poses", "walk_fast_poses", "wave_both_poses"]
    np.testing.assert_array_equal(library.clip_num_frames, [121, 91, 76])
    np.testing.assert_allclose(library.clip_duration, [4.0, 3.0, 2.5])
    np.testing.assert_array_equal(library.clip_start.numpy(), [0, 121, 212])
    frames = library.frames_device
    assert frames.body_pos.shape == (288, 24) and frames.body_rot.dtype == wp.quat
    assert frames.dof_pos.shape == (288, 69) and frames.dof_vel.shape == (288, 69)


def test_sample_kernel_matches_numpy_interpolation(library):
    rng = np.random.default_rng(0)
    clip_ids = rng.integers(0, 3, size=64).astype(np.int32)
    times = rng.uniform(-0.5, 4.5, size=64).astype(np.float32)  # includes times before/after the clip (clamped)
    times[:3] = [0.0, 1.0 / 30.0, 2.5]  # exact frame times
    clip_ids[:3] = [0, 1, 2]
    out = library.allocate_frames(64)
    library.sample(wp.array(clip_ids, dtype=int), wp.array(times, dtype=float), out)
    keys = ("body_pos", "body_rot", "body_vel", "body_angvel", "dof_pos", "dof_vel")
    got = {k: getattr(out, k).numpy() for k in keys}
    for i in range(64):
        want = reference_sample(library, int(clip_ids[i]), float(times[i]))
        for key in ("body_pos", "body_vel", "body_angvel", "dof_vel"):
            np.testing.assert_allclose(got[key][i], want[key], atol=2e-4, err_msg=key)
        assert np.all(np.abs(np.abs(np.sum(got["body_rot"][i] * want["body_rot"], -1)) - 1) < 1e-5)
        np.testing.assert_allclose(rot.wrap_angle(got["dof_pos"][i] - want["dof_pos"]), 0.0, atol=1e-4)
    # Exact frame times return the stored frames.
    np.testing.assert_allclose(got["body_pos"][0], library.clip(0)["body_pos"][0], atol=1e-6)
    np.testing.assert_allclose(got["body_pos"][1], library.clip(1)["body_pos"][1], atol=1e-6)
    np.testing.assert_allclose(got["body_pos"][2], library.clip(2)["body_pos"][-1], atol=1e-6)


def test_masked_sample_writes_only_the_selected_rows(library):
    rng = np.random.default_rng(1)
    ids = wp.array(rng.integers(0, 3, size=8).astype(np.int32), dtype=int)
    times = wp.array(rng.uniform(0.0, 3.0, size=8).astype(np.float32), dtype=float)
    full, masked = library.allocate_frames(8), library.allocate_frames(8)
    library.sample(ids, times, full)
    select = np.array([1, 0, 0, 1, 0, 1, 1, 0], dtype=bool)
    library.sample(ids, times, masked, mask=wp.array(select, dtype=wp.bool))
    for key in ("body_pos", "body_rot", "body_vel", "body_angvel", "dof_pos", "dof_vel"):
        got, want = getattr(masked, key).numpy(), getattr(full, key).numpy()
        np.testing.assert_array_equal(got[select], want[select], err_msg=key)
        assert not np.any(got[~select]), key  # untouched (still the zeros of allocate_frames)


def test_sample_interpolates_angles_the_short_way_and_is_capturable():
    # A hinge angle stepping from 3.1 to -3.1 rad turns 0.083 rad through +-pi, not 6.2 rad through 0.
    n = 2
    dof = np.zeros((n, 69))
    dof[0, 0], dof[1, 0] = 3.1, -3.1
    clip = MotionClip(
        "wrap",
        10.0,
        np.zeros((n, 24, 3)),
        rot.quat_identity((n, 24)),
        np.zeros((n, 24, 3)),
        np.zeros((n, 24, 3)),
        dof,
        np.zeros((n, 69)),
    )
    lib = MotionLibrary.from_clips([clip], device="cpu")
    out = lib.allocate_frames(3)
    ids = wp.zeros(3, dtype=int)
    times = wp.array(np.array([0.025, 0.05, 0.075], dtype=np.float32), dtype=float)
    lib.sample(ids, times, out)  # warm-up (loads the module), then capture and replay
    with wp.ScopedCapture(device="cpu") as capture:
        lib.sample(ids, times, out)
    out.dof_pos.zero_()
    wp.capture_launch(capture.graph)
    got = out.dof_pos.numpy()[:, 0]
    quarter = 0.25 * (2 * np.pi - 6.2)  # a quarter of the short way round
    np.testing.assert_allclose(rot.wrap_angle(got - np.array([3.1 + quarter, np.pi, -3.1 - quarter])), 0, atol=1e-5)


def test_save_load_round_trip(library, tmp_path):
    path = tmp_path / "lib.motionlib.npz"
    library.save(path)
    again = MotionLibrary.load(path, device="cpu", fps=60.0)  # a library file keeps its own rate
    assert again.fps == 30.0 and again.clip_names == library.clip_names and len(again.sources) == 3
    for key, value in library.frames.items():
        np.testing.assert_array_equal(again.frames[key], value)
    np.testing.assert_array_equal(again.clip_frames.numpy(), library.clip_frames.numpy())


def tamper(src, dst, **changes):
    with np.load(src) as data:
        arrays = {k: data[k] for k in data.files}
    for key, value in changes.items():
        if value is None:
            arrays.pop(key)
        else:
            arrays[key] = value(arrays) if callable(value) else value
    with open(dst, "wb") as f:
        np.savez(f, **arrays)
    return dst


def meta_with(**fields):
    def change(arrays):
        meta = json.loads(str(arrays["metadata"]))
        meta.update(fields)
        return np.array(json.dumps(meta))

    return change


def nan_at_frame(arrays):
    pos = arrays["body_pos"].copy()
    pos[5, 3, 1] = np.nan
    return pos


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"body_vel": None}, "missing key(s) ['body_vel']"),
        ({"metadata": np.array("not json")}, "'metadata' is not a JSON string"),
        ({"metadata": meta_with(version=99)}, "format version 99 is not supported"),
        ({"metadata": meta_with(format="other")}, "does not describe a 'refpo_warp.motionlib' file"),
        ({"metadata": meta_with(body_names=["Pelvis"])}, "body list differs"),
        ({"metadata": meta_with(fps=-1)}, "metadata 'fps' must be a positive number"),
        ({"clip_start": np.array([0, 121, 200])}, "'clip_start' does not match"),
        ({"clip_frames": np.array([121, 91])}, "'clip_frames' must be 3 integers"),
        ({"dof_pos": lambda a: a["dof_pos"][:, :60]}, "'dof_pos' has float32 (288, 60)"),
        ({"body_pos": nan_at_frame}, "'body_pos' has NaN or infinite values"),
        ({"body_rot": lambda a: 2 * a["body_rot"]}, "not unit length"),
    ],
)
def test_bad_library_files(library, tmp_path, changes, message):
    good = tmp_path / "good.motionlib.npz"
    library.save(good)
    bad = tamper(good, tmp_path / "bad.motionlib.npz", **changes)
    with pytest.raises(MotionDataError) as err:
        MotionLibrary.load(bad)
    assert str(bad) in str(err.value) and message in str(err.value)


def test_load_errors(tmp_path):
    with pytest.raises(MotionDataError, match="nothing_here: motion source not found"):
        MotionLibrary.load(tmp_path / "nothing_here")
    (tmp_path / "empty").mkdir()
    with pytest.raises(MotionDataError, match="empty: no AMASS motion files"):
        MotionLibrary.load(tmp_path / "empty")
    with pytest.raises(ValueError, match=r"fps=.* is invalid; expected a frame rate in \[1, 1000\]"):
        MotionLibrary.load(tmp_path / "empty", fps=0.0)


def test_library_frames_reproduce_in_mujoco():
    """Setting MuJoCo's free root to the library's pelvis pose and its hinges to ``dof_pos`` gives the library's
    body positions and rotations; its root velocities and ``dof_vel`` give (up to finite-difference error) the
    library's body velocities."""
    clip = generate_amass(with_fps(SPECS["walk_normal"], 120))
    lib = MotionLibrary.from_clips([_convert(clip, 120.0)], device="cpu")
    model = mujoco.MjModel.from_xml_string(skeleton_mjcf())
    data = mujoco.MjData(model)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in BODY_NAMES]
    f = lib.frames
    vel_err, ang_err = [], []
    for t in range(0, lib.num_frames, 7):
        root_rot = f["body_rot"][t, 0].astype(np.float64)
        data.qpos[:3], data.qpos[3:7], data.qpos[7:] = f["body_pos"][t, 0], np.roll(root_rot, 1), f["dof_pos"][t]
        data.qvel[:3] = f["body_vel"][t, 0]
        data.qvel[3:6] = rot.quat_rotate(rot.quat_conjugate(root_rot), f["body_angvel"][t, 0].astype(np.float64))
        data.qvel[6:] = f["dof_vel"][t]
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.xpos[ids], f["body_pos"][t], atol=2e-5)
        assert np.all(np.abs(np.abs(np.sum(np.roll(data.xquat[ids], -1, axis=1) * f["body_rot"][t], -1)) - 1) < 1e-5)
        for k, body in enumerate(ids):
            res = np.zeros(6)
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_XBODY, body, res, 0)
            ang_err.append(np.linalg.norm(res[:3] - f["body_angvel"][t, k]))
            vel_err.append(np.linalg.norm(res[3:] - f["body_vel"][t, k]))
    # Both sides are central differences at 120 fps of one smooth motion: they agree to finite-difference error.
    # (Measured: max 0.042 m/s at foot touch-downs, mean 5e-4 m/s; angular max 0.02, mean 2e-4 rad/s.)
    assert np.max(vel_err) < 0.08 and np.max(ang_err) < 0.05
    assert np.mean(vel_err) < 0.002 and np.mean(ang_err) < 0.002


def _convert(clip, fps):
    from refpo_warp.motion import kinematics as kin
    from refpo_warp.motion.clip import build_clip

    root_pos, root_rot, local = kin.amass_to_model(clip["root_orient"], clip["body_pose"], clip["trans"])
    return build_clip("walk", root_pos, root_rot, local, clip["fps"], fps)


def test_shipped_default_set_loads(tmp_path):
    from test_motion_synthetic import SHIPPED

    from refpo_warp.motion.clip import sole_heights

    lib = MotionLibrary.load(SHIPPED, device="cpu", fps=30.0)
    assert lib.num_clips == len(DEFAULT_CLIP_SPECS)
    for i, name in enumerate(lib.clip_names):
        spec = SPECS[name.removesuffix("_poses")]
        assert lib.clip_num_frames[i] == int(spec.duration * 30 + 1e-6) + 1
        # Grounded: the lowest sole point of the first second is on the floor.
        np.testing.assert_allclose(sole_heights(lib.clip(i)["body_pos"][:31]).min(), 0.0, atol=1e-5)


def test_convert_amass_command(amass_dir, library, tmp_path, capsys):
    from refpo_warp.cli.main import main

    out = tmp_path / "three.motionlib.npz"
    assert main(["convert-amass", str(amass_dir), f"out={out}", "fps=30"]) == 0
    converted = MotionLibrary.load(out)
    assert converted.clip_names == library.clip_names
    np.testing.assert_array_equal(converted.frames["dof_pos"], library.frames["dof_pos"])
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "x_poses.npz").write_text("garbage")
    assert (
        main(["convert-amass", str(tmp_path / "bad"), f"out={tmp_path / 'no.motionlib.npz'}"]) == 4
    )  # a bad input file
    assert "x_poses.npz: cannot be read as an npz archive" in capsys.readouterr().err
    assert not (tmp_path / "no.motionlib.npz").exists()


def test_sample_rejects_mismatched_sizes(library):
    out = library.allocate_frames(4)
    with pytest.raises(ValueError, match="3 clip ids and 4 times for 4 output rows"):
        library.sample(wp.zeros(3, dtype=int), wp.zeros(4, dtype=float), out)
