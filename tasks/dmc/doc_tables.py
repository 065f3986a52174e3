"""docs/dmc.md's tables of the tasks and of their env options, made from the code: ``refpo_warp.config.option_docs``
fills a page's ``<!-- table refpo_warp.tasks.dmc.doc_tables:<function> -->`` blocks, and
``tests/docs/test_option_tables.py`` fails when the page's table is not the one made here. Imports the suite's task
modules, and so Warp."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.dmc.cfg import DmcCfg, task_cfg_class
from refpo_warp.utils.option_tables import markdown_table, option_cells

MUJOCO_TIMESTEP = 0.002  # MuJoCo's default, where a model file's <option> sets none


def physics_dt(model_path) -> float:
    """The physics timestep of an MJCF file (its ``<option timestep>``)."""
    option = ET.parse(model_path).getroot().find("option")
    return float(option.get("timestep", MUJOCO_TIMESTEP)) if option is not None else MUJOCO_TIMESTEP


def tasks_table() -> str:
    """Each task's sizes, control step, reward and reset (the task classes' attributes and model files); a task whose
    module docstring names no Playground env is this project's, marked (ours)."""
    rows = []
    for name in suite.task_names():
        task = suite.task_class(name)
        dt = physics_dt(task.model_path())
        ours = "" if "Playground" in suite.describe(name) else " (ours)"
        rows.append(
            [
                f"`dmc_{name}`{ours}",
                str(task.num_obs),
                str(task.num_actions),
                f"{dt * task.substeps:g} = {dt:g} x {task.substeps}",
                task.reward_summary,
                task.reset_summary,
            ]
        )
    header = ["task id", "obs", "act", "control dt = physics dt x substeps", "reward (per step, max 1)", "reset"]
    return markdown_table(header, rows)


def options_table() -> str:
    """The family's env options (``DmcCfg``'s, every DMC task), then each task's own (its ``<task>_cfg.py``)."""
    rows = [[cells[0], "every DMC task", *cells[1:]] for cells in option_cells(DmcCfg)]
    for name in suite.task_names():
        cfg_class = task_cfg_class(name)
        if cfg_class is not DmcCfg:
            rows += [[cells[0], f"`dmc_{name}`", *cells[1:]] for cells in option_cells(cfg_class)]
    return markdown_table(["option", "tasks", "default", "valid values", "meaning"], rows)
