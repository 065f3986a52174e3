"""The module layers of the project (``docs/architecture.md``) and the static import graph they are checked against.

A module may import modules of its own layer and of the layers below, never above; ``tests/test_layering.py``
checks this, and that the graph has no circles, on every run. ``tools/draw_layers.py`` draws it.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Top to bottom: the refpo_warp modules (first name below refpo_warp) of each layer.
LAYERS = {
    "cli": ["cli"],
    "app": ["training", "report", "latency", "algorithm_bench", "sweep", "sweep_report", "sweep_plots", "plots",
            "tables", "layering"],
    "run": ["runner", "runner_setup", "config", "run_dir", "run_options", "registry", "checkpoints", "progress",
            "evaluation", "distributed", "flow_diagnostics", "sweep_spec"],
    "core": ["algorithms", "models", "envs", "sim", "motion"],
    "base": ["errors", "options", "device", "atomic", "console", "benchmarking", "task_spec", "rsl_rl_rules",
             "rsl_rl_compat"],
}  # fmt: skip
LAYER_RANK = {layer: rank for rank, layer in enumerate(reversed(LAYERS))}
_RANK = {name: LAYER_RANK[layer] for layer, names in LAYERS.items() for name in names}
FAMILY_TOOLS = ("bench", "report", "probe_episodes", "profile_step")
"""Modules of a task family that are tools (they build envs through the registry): layer ``app``; the rest of a
family (its task list, cfg, env and kernels) is env code: layer ``core``."""


def first_party_modules(root: Path = ROOT) -> dict[str, Path]:
    """Every module of ``refpo_warp`` and ``tasks`` by dotted name (a package by its own name)."""
    modules = {}
    for path in sorted([*root.glob("refpo_warp/**/*.py"), *root.glob("tasks/**/*.py")]):
        name = ".".join(path.relative_to(root).with_suffix("").parts)
        modules[name.removesuffix(".__init__")] = path
    return modules


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Static imports between first-party modules, function-level (lazy) imports included; ``importlib`` calls by
    name (the registry finding task families) are not edges."""

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


def layer_of(module: str) -> str | None:
    """The layer of a first-party module (None for the two root packages and unknown names)."""
    parts = module.split(".")
    if parts[0] == "refpo_warp" and len(parts) > 1:
        return next((layer for layer, names in LAYERS.items() if parts[1] in names), None)
    if parts[0] == "tasks" and len(parts) > 1:
        return "app" if parts[-1] in FAMILY_TOOLS else "core"
    return None


def upward_imports(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports from a module into a higher layer than its own."""
    out = []
    for module, targets in sorted(graph.items()):
        for target in sorted(targets):
            a, b = layer_of(module), layer_of(target)
            if a is not None and b is not None and LAYER_RANK[b] > LAYER_RANK[a]:
                out.append((module, target))
    return out


def modules_on_circles(graph: dict[str, set[str]]) -> list[str]:
    """Modules on an import circle: what is left after repeatedly removing modules that import nothing left."""
    left = {m: set(t) for m, t in graph.items()}
    while True:
        leaves = [m for m, t in left.items() if not t & left.keys()]
        if not leaves:
            return sorted(left)
        for m in leaves:
            del left[m]
