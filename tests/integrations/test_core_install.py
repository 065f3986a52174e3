"""The core install (no extras) is what goes into someone else's simulator stack (docs/mjlab.md): the algorithms,
the models, the statistics logger and the class-option reader import without any distribution of the ``sim`` extra
(read from pyproject.toml: Warp, Newton, gymnasium, matplotlib, imageio, ...) that the core's own dependencies do not
bring themselves (rsl-rl-lib >= 5.4 requires TensorBoard)."""

import json
import re
import subprocess
import sys
from importlib.metadata import packages_distributions, requires

import tomllib

from refpo_warp.utils.paths import REPO_ROOT

CORE_MODULES = [
    "refpo_warp.algorithms",
    "refpo_warp.models",
    "refpo_warp.integrations.statistics_logger",
    "refpo_warp.config.classes",
]


def name(requirement: str) -> str:
    return re.split(r"[\[<>=~!; (]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def sim_extra_imports() -> list[str]:
    """Top-level import names of the ``sim`` extra's distributions (those installed here)."""
    project = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["project"]
    core = {name(req) for req in project["dependencies"]}
    brought = {name(req) for dist in core for req in requires(dist) or [] if "extra ==" not in req}
    dists = {name(req) for req in project["optional-dependencies"]["sim"]} - brought
    assert not dists & core
    return sorted(
        module
        for module, owners in packages_distributions().items()
        if {name(o) for o in owners} & dists and not module.startswith("_")
    )


def test_the_core_imports_without_the_sim_extra():
    blocked = sim_extra_imports()
    assert {"warp", "newton", "gymnasium", "matplotlib", "imageio"} <= set(blocked), blocked
    script = f"""
import json, sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {blocked!r}:
            raise ImportError("the sim extra's " + name)
sys.meta_path.insert(0, Block())
for module in {CORE_MODULES!r}:
    __import__(module)
from refpo_warp.config.classes import class_defaults
class_defaults("refpo_warp.algorithms:ReFPO"), class_defaults("refpo_warp.models:FlowActor")
print(json.dumps("ok"))
"""
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300, check=False
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == "ok"
