"""The package as a user installs it: the wheel built from this checkout, installed (not editable) into a fresh venv
that sees this environment's dependencies (nothing is downloaded), used from a directory outside the checkout with the
console command: train GridWorld, evaluate it, explain an option, list the tasks with one from a config folder of
one's own, and dry-run a sweep."""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from refpo_warp.utils.paths import REPO_ROOT

TINY = [
    "task=gridworld",
    "device=cpu",
    "max_iterations=2",
    "num_envs=8",
    "runner.num_steps_per_env=16",
    "eval.num_envs=8",
    "eval.flow_steps=[1]",
]


def run(cmd: list[str], cwd: Path, env: dict) -> subprocess.CompletedProcess:
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, (
        f"{' '.join(cmd)}: exit {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}"
    )
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(the fresh venv's bin folder, its environment): the wheel installed there, this environment's
    site-packages behind it on sys.path (a path line, so the editable install's import hook is not loaded)."""
    root = tmp_path_factory.mktemp("wheel")
    source = root / "source"  # the checkout's files, without a build/ folder an earlier build may have left stale
    files = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=REPO_ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split("\n")
    for name in filter(None, files):
        if (REPO_ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(REPO_ROOT / name, source / name)
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(root / "dist"),
            str(source),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (wheel,) = (root / "dist").glob("refpo_warp-*.whl")
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    site = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    Path(site, "ci_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(python),
            "install",
            "--quiet",
            "--no-deps",
            "--no-index",
            str(wheel),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "REFPO_CONFIG_PATH", "VIRTUAL_ENV")}
    env["PATH"] = os.pathsep.join([str(venv / "bin"), env.get("PATH", "")])
    return venv / "bin", env


@pytest.mark.slow(minutes=0.4)
def test_the_wheel_trains_evaluates_explains_lists_and_sweeps_outside_the_checkout(installed, tmp_path):
    bin_dir, env = installed
    refpo = str(bin_dir / "refpo")
    where = run([str(bin_dir / "python"), "-c", "import refpo_warp; print(refpo_warp.__file__)"], tmp_path, env)
    assert Path(where.stdout.strip()).is_relative_to(bin_dir.parent), where.stdout  # the wheel's copy, not ours

    trained = run([refpo, "train", *TINY, "run_dir=run1"], tmp_path, env)
    assert (tmp_path / "run1" / "model_1.pt").is_file() and "N=1" in trained.stdout
    run([refpo, "eval", "run_dir=run1", "eval.flow_steps=[1]"], tmp_path, env)
    assert (tmp_path / "run1" / "eval.prev.json").is_file()

    clip = run(
        [
            str(bin_dir / "python"),
            "-c",
            (
                "from refpo_warp.config.resolve import resolve_config as c; "
                "from refpo_warp.tasks.humanoid.motions import resolve_motion_file as r; "
                "print(r(c(['task=humanoid_all_residual'], device_type='cpu')['env']['motion_file']))"
            ),
        ],
        tmp_path,
        env,
    )
    assert Path(clip.stdout.strip()).is_file() and Path(clip.stdout.strip()).is_relative_to(bin_dir.parent), clip.stdout

    explained = run([refpo, "train", "task=gridworld", "algo=fpo", "--explain", "algorithm.reflow_coef"], tmp_path, env)
    assert "algorithm.reflow_coef = 0.0\n  set by  configs/algo/fpo.yaml" in explained.stdout

    (tmp_path / "mine" / "task").mkdir(parents=True)
    (tmp_path / "mine" / "task" / "grid_small.yaml").write_text("base: gridworld\nnum_envs: 8\n")
    listed = run([refpo, "train", "--list-tasks", "config_dir=mine"], tmp_path, env).stdout
    assert "dmc_cartpole_balance" in listed and "grid_small" in listed

    swept = run([refpo, "sweep", "cpu_dmc", "--dry-run"], tmp_path, env).stdout
    assert "python -m refpo_warp train" not in swept and "refpo train task=dmc_point_mass" in swept
    assert not (tmp_path / "runs").exists()  # a dry run writes nothing
