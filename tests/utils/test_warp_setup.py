"""Warp is configured in one place (``refpo_warp/utils/warp_setup.py``) that every Warp-using module reaches through its
own import: no module imports ``warp`` itself, and every module that defines Warp kernels or functions, imported alone
in a fresh interpreter (Warp loaded before it, unconfigured, as another library may do), defines them with Warp's
options set."""

import ast

from fresh_imports import import_each_alone  # tests/utils is on sys.path under pytest

from refpo_warp.utils.layering import first_party_modules

SETUP = "refpo_warp.utils.warp_setup"
DEFINES = ("wp.kernel", "wp.func", "wp.struct", "wp.constant")  # what freezes a Warp module's options


def imports_warp(tree: ast.AST) -> bool:
    for node in ast.walk(tree):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names = [node.module]
        if any(n == "warp" or n.startswith("warp.") for n in names):
            return True
    return False


def test_only_the_setup_module_imports_warp():
    direct = [
        name
        for name, path in first_party_modules().items()
        if name != SETUP and imports_warp(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert not direct, f"modules that import warp themselves instead of `from {SETUP} import wp`: {direct}"


def test_each_warp_module_imported_alone_defines_its_kernels_with_the_options_set():
    modules = [
        name
        for name, path in first_party_modules().items()
        if any(d in path.read_text(encoding="utf-8") for d in DEFINES) and name != SETUP
    ]
    assert "refpo_warp.tasks.dmc.suite.cartpole_balance" in modules and "refpo_warp.tasks.dmc.rewards" in modules
    check = """
options = warp.get_module(name).options
if warp.config.enable_backward is not False or options["enable_backward"] is not False:
    msg = f"enable_backward: config {warp.config.enable_backward}, module {options['enable_backward']}"
"""
    failed = import_each_alone(modules, "import numpy, torch, warp  # Warp loaded first, with its own defaults", check)
    assert not failed, "\n".join(f"{k}: {v}" for k, v in failed.items())
