"""Module layering (docs/architecture.md): imports go one way, there are no circles, every module imports on its own
in a fresh interpreter, and resolving a config loads no simulator (Warp, Newton)."""

import ast
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Layers from the top; a module may import its own layer and the layers below, never one above.
LAYERS = {
    "cli": ["cli"],
    "app": ["training", "report", "latency", "algorithm_bench", "sweep", "sweep_report", "sweep_plots", "plots",
            "tables"],
    "run": ["runner", "runner_setup", "config", "run_dir", "run_options", "registry", "checkpoints", "progress",
            "evaluation", "distributed", "flow_diagnostics", "sweep_spec"],
    "core": ["algorithms", "models", "envs", "sim", "motion"],
    "base": ["errors", "options", "device", "atomic", "benchmarking", "task_spec", "rsl_rl_rules", "rsl_rl_compat"],
}  # fmt: skip
LAYER_RANK = {layer: rank for rank, layer in enumerate(reversed(LAYERS))}
RANK = {name: LAYER_RANK[layer] for layer, names in LAYERS.items() for name in names}
# Task-family modules that are tools (they build envs through the registry or train); the rest is env code.
FAMILY_TOOLS = ("bench", "report", "probe_episodes", "profile_step")


def first_party_modules() -> dict[str, Path]:
    modules = {}
    for path in sorted([*ROOT.glob("refpo_warp/**/*.py"), *ROOT.glob("tasks/**/*.py")]):
        name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        modules[name.removesuffix(".__init__")] = path
    return modules


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Static imports between first-party modules, function-level (lazy) imports included."""

    def owner(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in modules.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                found = [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
            else:
                continue
            targets |= {t for t in map(owner, found) if t and t != name and not name.startswith(f"{t}.")}
        graph[name] = targets
    return graph


def layer_of(module: str) -> int | None:
    parts = module.split(".")
    if parts[0] == "refpo_warp" and len(parts) > 1:
        return RANK.get(parts[1])
    if parts[0] == "tasks":  # env code sits with the envs; family tools with the applications
        return LAYER_RANK["app"] if parts[-1] in FAMILY_TOOLS else LAYER_RANK["core"]
    return None


def test_every_module_has_a_layer():
    missing = [m for m in first_party_modules() if m not in ("refpo_warp", "tasks") and layer_of(m) is None]
    assert not missing, f"modules without a layer in tests/test_layering.py (and docs/architecture.md): {missing}"


def test_imports_go_one_way_without_circles():
    graph = import_graph(first_party_modules())
    upward = [(m, t) for m, targets in graph.items() for t in targets
              if layer_of(m) is not None and layer_of(t) is not None and layer_of(t) > layer_of(m)]  # fmt: skip
    assert not upward, f"imports from a lower layer into a higher one: {upward}"
    # No circles: repeatedly drop modules that import nothing left; whatever remains lies on a circle.
    left = {m: set(t) for m, t in graph.items()}
    while True:
        leaves = [m for m, t in left.items() if not t & left.keys()]
        if not leaves:
            break
        for m in leaves:
            del left[m]
    assert not left, f"import circles among: {sorted(left)}"


def test_each_module_imports_alone_in_a_fresh_interpreter():
    """One fresh process per module (forked from a parent that loaded only third-party packages): a module that
    works only after another first-party module was imported fails here."""
    names = [m for m in first_party_modules() if not m.endswith("__main__")]
    script = f"""
import json, os, sys, traceback
import numpy, torch, yaml, rsl_rl.runners  # third-party only
failed = {{}}
for name in {names!r}:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        try:
            __import__(name)
            code, msg = 0, b""
        except BaseException:
            code, msg = 1, traceback.format_exc().encode()[-2000:]
        os.write(w, msg)
        os._exit(code)
    os.close(w)
    msg = os.read(r, 4000).decode()
    os.close(r)
    if os.waitpid(pid, 0)[1] != 0:
        failed[name] = msg
print(json.dumps(failed))
"""
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    failed = json.loads(out.stdout.strip().splitlines()[-1])
    assert not failed, "\n".join(f"{k}:\n{v}" for k, v in failed.items())


def test_resolving_configs_loads_no_simulator():
    script = """
import sys, json
from refpo_warp.config import resolve_config
from refpo_warp.registry import list_tasks, make_env_cfg
for task in list_tasks():
    resolve_config({"task": task, "device": "cpu"})
    make_env_cfg(task)
print(json.dumps(sorted(m for m in ("warp", "newton", "mujoco", "mujoco_warp") if m in sys.modules)))
"""
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
