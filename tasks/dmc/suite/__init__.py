"""The DMC suite: one module per task, named by the task (``cartpole_balance.py`` is ``dmc_cartpole_balance``).

A task module defines one ``DmcTask`` subclass (``tasks/dmc/task.py``) and opens with a one-line docstring that
describes the task. The names and descriptions are read from the files without importing them (no Warp); a task's
module is imported when an env of that task is built.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from refpo_warp.tasks.dmc.task import DmcTask

SUITE_DIR = Path(__file__).resolve().parent


def task_names() -> list[str]:
    """Every suite task, sorted: the modules of this package."""
    return sorted(m.name for m in pkgutil.iter_modules([str(SUITE_DIR)]) if not m.name.startswith("_"))


def describe(name: str) -> str:
    """The first line of the task module's docstring (parsed, not imported), as plain text."""
    doc = ast.get_docstring(ast.parse((SUITE_DIR / f"{name}.py").read_text(encoding="utf-8"))) or ""
    return doc.split("\n", 1)[0].replace("``", "").rstrip(".")


def task_class(name: str) -> type[DmcTask]:
    """The ``DmcTask`` subclass that the module ``name`` defines (importing the module, and so Warp)."""
    from refpo_warp.tasks.dmc.task import DmcTask

    module = importlib.import_module(f"{__name__}.{name}")
    found = [
        c
        for c in vars(module).values()
        if isinstance(c, type) and issubclass(c, DmcTask) and c.__module__ == module.__name__
    ]
    if len(found) != 1:
        raise TypeError(f"{module.__file__} must define exactly one DmcTask subclass, found {len(found)}")
    return found[0]
