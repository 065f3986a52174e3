"""``refpo bench dmc`` measures every suite task by default, dmc_point_mass_wall beside point_mass; its table's ratios
are the quotients of the rates it prints beside them (its anchor, MuJoCo C on the same file, measured in the same
run). Tiny sizes: the figures themselves are the benchmark's business, not a test's."""

from __future__ import annotations

import pytest

from refpo_warp.cli.main import main
from refpo_warp.tasks.dmc.bench import task_ids
from refpo_warp.tasks.dmc.suite import task_names

pytest.importorskip("mujoco")


def test_the_default_list_is_every_suite_task():
    assert task_ids() == [f"dmc_{t}" for t in task_names()]
    assert {"dmc_point_mass", "dmc_point_mass_wall"} <= set(task_ids())


def test_the_wall_task_is_measured_against_mujoco_c_beside_point_mass(capsys):
    argv = ["bench", "dmc", "tasks=[dmc_point_mass,dmc_point_mass_wall]", "device=cpu", "num_envs=2"]
    assert main([*argv, "timed_seconds=0.05"]) == 0
    lines = capsys.readouterr().out.splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("| task"))
    columns = [c.strip() for c in lines[header].strip("|").split("|")]
    rows = {}
    for line in lines[header + 2 : header + 4]:
        cells = dict(zip(columns, (c.strip() for c in line.strip("|").split("|")), strict=True))
        rows[cells["task"]] = cells
    assert set(rows) == {"point_mass", "point_mass_wall"}
    for row in rows.values():
        ours = float(row["ours (env steps/s)"].replace(",", ""))
        for c in ("C rollout", "C loop"):
            rate = float(row[c].replace(",", ""))
            assert ours > 0 and rate > 0
            # the printed ratio, from the unrounded rates: within the rounding of the printed ones
            assert float(row[f"ours / {c}"]) == pytest.approx(ours / rate, abs=0.006 + ours / rate * 1e-3)
