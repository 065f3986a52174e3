"""Module layering (docs/architecture.md): imports go one way, there are no circles, every module imports on its own
in a fresh interpreter (an integration's only where its framework is installed), and resolving a config loads no
simulator (Warp, Newton)."""

import importlib.util
import json
import subprocess
import sys

from fresh_imports import import_each_alone  # tests/utils is on sys.path under pytest

from refpo_warp.utils.layering import (
    ROOT,
    first_party_modules,
    framework_needed,
    import_graph,
    layer_of,
    upward_imports,
)


def modules_on_circles(graph: dict[str, set[str]]) -> list[str]:
    """Modules on an import circle: what is left after repeatedly removing modules that import nothing left."""
    left = {m: set(t) for m, t in graph.items()}
    while True:
        leaves = [m for m, t in left.items() if not t & left.keys()]
        if not leaves:
            return sorted(left)
        for m in leaves:
            del left[m]


def test_every_module_has_a_layer():
    missing = [m for m in first_party_modules() if m != "refpo_warp" and layer_of(m) is None]
    assert not missing, f"modules without a layer in refpo_warp/utils/layering.py (and docs/architecture.md): {missing}"


def test_imports_go_one_way_without_circles():
    graph = import_graph(first_party_modules())
    assert not upward_imports(graph), f"imports from a lower layer into a higher one: {upward_imports(graph)}"
    assert not modules_on_circles(graph), f"import circles among: {modules_on_circles(graph)}"


def test_each_module_imports_alone_in_a_fresh_interpreter():
    """One fresh process per module (forked from a parent that loaded only third-party packages): a module that
    works only after another first-party module was imported fails here."""

    def importable(module: str) -> bool:
        framework = framework_needed(module)
        return framework is None or importlib.util.find_spec(framework) is not None

    names = [m for m in first_party_modules() if not m.endswith("__main__") and importable(m)]
    # Heavy third-party packages load once, in the parent (52 s -> 22 s for the 219 modules here). Not mujoco: forked
    # from a parent that loaded it under MUJOCO_GL=egl (conftest.py), the children took 137 s; nor newton (30 s).
    preload = "import numpy, torch, yaml, rsl_rl.runners, warp, matplotlib.pyplot  # third-party only"
    failed = import_each_alone(names, preload)
    assert not failed, "\n".join(f"{k}:\n{v}" for k, v in failed.items())


def test_resolving_configs_loads_no_simulator():
    script = """
import sys, json
from refpo_warp.config.resolve import resolve_config
from refpo_warp.envs.registry import list_tasks, make_env_cfg
for task in list_tasks():
    resolve_config({"task": task, "device": "cpu"})
    make_env_cfg(task)
print(json.dumps(sorted(m for m in ("warp", "newton", "mujoco", "mujoco_warp") if m in sys.modules)))
"""
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=300, check=False
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
