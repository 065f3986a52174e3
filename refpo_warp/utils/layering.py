"""The layers of the project (``docs/architecture.md``): each folder of ``refpo_warp/`` belongs to one layer, and a
module's layer is its folder's. A module may import its own layer and the layers below, never above;
``tests/utils/test_layering.py`` checks this, and that the import graph has no circles, on every run.
``docs/figures/draw_layers.py`` draws it.
"""

from __future__ import annotations

import ast
from pathlib import Path

from refpo_warp.utils.paths import REPO_ROOT as ROOT

PACKAGE = "refpo_warp"

# Top to bottom: the folders (first name below refpo_warp) of each layer. refpo_warp.tasks is the repository's tasks/;
# refpo_warp/__main__.py (python -m refpo_warp) is the command line too.
LAYERS = {
    "cli": ["cli", "__main__"],
    "app": ["training", "evaluation", "demonstrations", "studies", "benchmarks", "integrations"],
    "run": ["config", "runner"],
    "core": ["algorithms", "models", "envs", "sim", "motion", "render", "tasks"],
    "base": ["utils"],
}
LAYER_RANK = {layer: rank for rank, layer in enumerate(reversed(LAYERS))}
# Packages that glue the project to another framework import it at the top and are loaded by it (an entry point):
# they import alone only where that framework is installed (package prefix -> the module it needs).
NEEDS_FRAMEWORK = {"refpo_warp.integrations.mjlab": "mjlab"}
FOLDER_LAYER = {folder: layer for layer, folders in LAYERS.items() for folder in folders}


def first_party_modules(root: Path = ROOT) -> dict[str, Path]:
    """Every module of the installed package by dotted name (a package by its own name); ``tasks/`` is
    ``refpo_warp.tasks``."""
    modules = {}
    for folder, prefix in ((root / PACKAGE, (PACKAGE,)), (root / "tasks", (PACKAGE, "tasks"))):
        for path in sorted(folder.glob("**/*.py")):
            name = ".".join(prefix + path.relative_to(folder).with_suffix("").parts)
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


def framework_needed(module: str) -> str | None:
    """The framework a first-party module needs in order to import (``NEEDS_FRAMEWORK``), or None."""
    for prefix, framework in NEEDS_FRAMEWORK.items():
        if module == prefix or module.startswith(prefix + "."):
            return framework
    return None


def layer_of(module: str) -> str | None:
    """The layer of a first-party module: its folder's (None for the package root and unknown folders)."""
    parts = module.split(".")
    return FOLDER_LAYER.get(parts[1]) if parts[0] == PACKAGE and len(parts) > 1 else None


def upward_imports(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports from a module into a higher layer than its own."""
    out = []
    for module, targets in sorted(graph.items()):
        for target in sorted(targets):
            a, b = layer_of(module), layer_of(target)
            if a is not None and b is not None and LAYER_RANK[b] > LAYER_RANK[a]:
                out.append((module, target))
    return out
