"""Every code reference of the user-facing pages (README.md and docs/*.md, the top level only: the results pages under
docs/results/ are written by their scripts and checked by tests/docs/test_results_pages.py) resolves in this
repository. What counts as a reference, in the pages' text outside fenced code blocks:

- a repository path, backticked or not followed by a line: a path whose first folder is one of this repository's
  top-level folders (``REPO_FOLDERS``); it exists, and ``path:line`` / ``path:line-line`` are lines of the file. A
  path under another folder (FPO++'s ``algorithms/fpo.py:511-533``, mjlab's ``rl_cfg.py:101``) names another project's
  file and is not checked; neither is a path with a placeholder (``tasks/<family>/cfg.py``, ``configs/task/*.yaml``)
  nor one of ``NOT_HERE`` (files the pages tell a reader to create, and another project's file under a name that
  starts like ours);
- ``Class.attr`` in backticks: a CamelCase name (a capital first, no underscore: not ``NUM_FLOW_STEPS``, not
  ``torch.compile``, ``np.float32``, ``wp.launch`` or ``config.yaml``) that is not itself part of a dotted name,
  followed by attributes (``ReFPO.policy_loss``, ``FlowActor.Options``, ``OnPolicyRunner.load()``). The class is
  defined in refpo_warp/ or tasks/ (found by parsing the source with ``ast``, nothing imported) or, for another
  project's class the pages name (rsl_rl's ``PPO``, Newton's ``SolverMuJoCo``), in that package as installed
  (``OTHER_PACKAGES``; skipped where it is not installed). Its attributes are its methods, class-level assignments,
  annotated (dataclass) fields, nested classes, the ``self.<name>`` its methods assign, and its bases' (by name);
  a nested class's attributes follow (``FlowActor.Options.num_flow_steps``);
- ``refpo_warp.<module>[.<name>...]`` and ``refpo_warp.<module>:<Name>`` in backticks (a ``class_name``): the module
  is a file or package of refpo_warp/ (``refpo_warp.tasks`` is tasks/, ``refpo_warp.configs`` is configs/) and the
  name is defined or imported at its top level (an import followed to its module), then attributes as above (a
  quoted value, ``"refpo_warp.motionlib"``, is a string, not a module);
- a Markdown link to a local file: the file exists, and its ``#anchor`` is one of that page's headings.

A failure names the page and line, and the reference.
"""

from __future__ import annotations

import ast
import importlib.util
import re
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
REPO_FOLDERS = ("refpo_warp", "tasks", "tests", "configs", "docs", "tools", "examples", ".ci")
NOT_HERE = (
    "tasks/line/",  # docs/create_new_task.md: the task a reader creates
    "configs/task/line.yaml",
    "configs/algo/capped_reflow.yaml",  # docs/create_new_task.md: the algorithm a reader creates
    "tools/fpo_training_receipts/",  # FPO++'s repository (amazon-far/fpo-control)
)
OTHER_PACKAGES = ("rsl_rl", "newton")
MODULE_DIRS = {"refpo_warp.tasks": ROOT / "tasks", "refpo_warp.configs": ROOT / "configs"}

FENCE = re.compile(r"^ *```.*?^ *```", re.DOTALL | re.MULTILINE)
SPAN = re.compile(r"`([^`]+)`")
PATH = re.compile(
    r"(?<![\w./-])((?:" + "|".join(re.escape(f) for f in REPO_FOLDERS) + r")/[\w./<>*{}-]*)(?::(\d+)(?:-(\d+))?)?"
)
CLASS_ATTR = re.compile(r"(?<![\w.:/])([A-Z][A-Za-z0-9]*(?:\.[A-Za-z_]\w*)+)")
MODULE = re.compile(r"(?<![\w./\"'])(refpo_warp(?:\.\w+)+)(?::(\w+(?:\.\w+)*))?")
LINK = re.compile(r"\]\(([^)\s]+)\)")


@dataclass
class ClassInfo:
    attrs: set[str] = field(default_factory=set)
    bases: list[str] = field(default_factory=list)
    nested: dict[str, ClassInfo] = field(default_factory=dict)


def _class_info(node: ast.ClassDef) -> ClassInfo:
    info = ClassInfo(bases=[b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", "") for b in node.bases])
    for item in node.body:
        if isinstance(item, ast.ClassDef):
            info.nested[item.name] = _class_info(item)
            info.attrs.add(item.name)
        elif isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
            info.attrs.add(item.name)
            for sub in ast.walk(item):  # self.<name> = ... in a method
                targets = sub.targets if isinstance(sub, ast.Assign) else [getattr(sub, "target", None)]
                for t in targets:
                    if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name) and t.value.id == "self":
                        info.attrs.add(t.attr)
        elif isinstance(item, ast.Assign):
            info.attrs.update(t.id for t in item.targets if isinstance(t, ast.Name))
        elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
            info.attrs.add(item.target.id)
    return info


@cache
def _parsed(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


@cache
def _sources(folder: Path) -> list[tuple[Path, str]]:
    return [(path, path.read_text(encoding="utf-8")) for path in sorted(folder.rglob("*.py"))]


def _defined_in(folders: list[Path], name: str) -> list[ClassInfo]:
    """Every class ``name`` defined in ``folders`` (only the files that hold ``class <name>`` are parsed)."""
    found: list[ClassInfo] = []
    pattern = re.compile(rf"^\s*class {re.escape(name)}\b", re.MULTILINE)
    for folder in folders:
        for path, text in _sources(folder):
            if pattern.search(text):
                found += [
                    _class_info(n) for n in ast.walk(_parsed(path)) if isinstance(n, ast.ClassDef) and n.name == name
                ]
    return found


@cache
def installed(package: str) -> list[Path] | None:
    spec = importlib.util.find_spec(package)  # finds the package without importing it
    return [Path(p) for p in spec.submodule_search_locations] if spec and spec.submodule_search_locations else None


@cache
def _classes(name: str) -> list[ClassInfo]:
    found = _defined_in([ROOT / "refpo_warp", ROOT / "tasks"], name)
    for package in OTHER_PACKAGES:
        found += _defined_in(installed(package) or [], name)
    return found


def _has(infos: list[ClassInfo], attr: str, seen: set[int] | None = None) -> list[ClassInfo] | None:
    """The classes ``attr`` names (a nested class's info, or [] for any other attribute) if one of ``infos`` or
    their bases has it, else None."""
    seen = set() if seen is None else seen
    for info in infos:
        if id(info) in seen:
            continue
        seen.add(id(info))
        if attr in info.nested:
            return [info.nested[attr]]
        if attr in info.attrs:
            return []
        inherited = _has([b for name in info.bases for b in _classes(name)], attr, seen)
        if inherited is not None:
            return inherited
    return None


def _check_attrs(infos: list[ClassInfo], attrs: list[str], shown: str) -> str | None:
    for attr in attrs:
        if not infos:
            return None  # an attribute of a plain attribute (a field's value): not checked
        found = _has(infos, attr)
        if found is None:
            return f"{shown}: no attribute '{attr}'"
        infos = found
    return None


def check_class_attr(ref: str) -> str | None:
    """None when ``Class.attr[.attr...]`` resolves, else why not; "skip" for a class of a package not installed."""
    name, *attrs = ref.split(".")
    infos = _classes(name)
    if not infos:
        if any(installed(p) is None for p in OTHER_PACKAGES):
            return "skip"
        return f"{ref}: no class '{name}' in refpo_warp/, tasks/ or {', '.join(OTHER_PACKAGES)}"
    return _check_attrs(infos, attrs, ref)


def _module_file(module: str) -> Path | None:
    for prefix, folder in MODULE_DIRS.items():
        if module == prefix or module.startswith(prefix + "."):
            base = folder / module[len(prefix) + 1 :].replace(".", "/") if module != prefix else folder
            break
    else:
        base = ROOT / module.replace(".", "/")
    if (base / "__init__.py").exists():
        return base / "__init__.py"
    if base.with_suffix(".py").exists():
        return base.with_suffix(".py")
    return base if base.is_dir() else None  # a folder of data (refpo_warp.configs)


def _top_level(path: Path, name: str, depth: int = 0) -> list[ClassInfo] | None:
    """What ``name`` is at the top level of the module in ``path``: a class's info, [] for anything else, None if
    the module neither defines nor imports it (an import is followed to its module)."""
    if path.suffix != ".py" or depth > 5:
        return None
    for node in _parsed(path).body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            return [_class_info(node)]
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == name:
            return []
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
            return []
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.target.id == name:
            return []
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    source = _module_file(node.module) if node.module.startswith("refpo_warp") else None
                    return (_top_level(source, alias.name, depth + 1) or []) if source else []
    return None


def check_module(module: str, names: str | None) -> str | None:
    """None when ``refpo_warp.a.b[.Name...]`` or ``refpo_warp.a.b:Name[.attr]`` resolves, else why not."""
    parts = module.split(".")
    if names is None:  # the longest prefix that is a module, the rest names in it
        for cut in range(len(parts), 0, -1):
            if _module_file(".".join(parts[:cut])) is not None:
                module, rest = ".".join(parts[:cut]), parts[cut:]
                break
        else:
            return f"{module}: no such module"
    else:
        rest = names.split(".")
    path = _module_file(module)
    if path is None:
        return f"{module}: no such module"
    if not rest:
        return None
    infos = _top_level(path, rest[0])
    if infos is None:
        return f"{module}: defines or imports no '{rest[0]}'"
    return _check_attrs(infos, rest[1:], f"{module}.{'.'.join(rest)}")


def check_path(path: str, first: str | None, last: str | None) -> str | None:
    """None when a repository path (and its lines) exists, else why not."""
    target = ROOT / path
    if not target.exists():
        return f"{path}: no such file or folder"
    if first is None:
        return None
    n = len(target.read_text(encoding="utf-8").splitlines()) if target.is_file() else 0
    lo, hi = int(first), int(last or first)
    if not 1 <= lo <= hi <= n:
        return f"{path}:{first}{'-' + last if last else ''}: the file has {n} lines"
    return None


def _slug(heading: str) -> str:
    # GitHub's: lower case, punctuation other than - and _ dropped, each space a -
    return re.sub(r"[^\w\s-]", "", heading.strip().lower()).replace(" ", "-")


def check_link(page: Path, target: str) -> str | None:
    """None when a local link's file (and its heading anchor) exists, else why not."""
    if re.match(r"[a-z]+:", target):  # https:, mailto:
        return None
    file, _, anchor = target.partition("#")
    path = (page.parent / file).resolve() if file else page
    if not path.exists():
        return f"link {target}: no such file"
    if anchor and path.suffix == ".md":
        text = FENCE.sub("", path.read_text(encoding="utf-8"))
        if anchor not in {_slug(h) for h in re.findall(r"^#+ (.*)$", text, re.MULTILINE)}:
            return f"link {target}: no heading with that anchor"
    return None


def references(page: Path) -> list[tuple[int, str, str | None]]:
    """(line, reference, None or why it does not resolve) for every reference of ``page``."""
    raw = page.read_text(encoding="utf-8")
    text = FENCE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), raw)  # blank the fenced blocks, keep the lines
    out: list[tuple[int, str, str | None]] = []

    def line(pos: int) -> int:
        return text.count("\n", 0, pos) + 1

    spans = [(m.start(1), m.group(1).replace("\n", " ")) for m in SPAN.finditer(text)]
    for m in PATH.finditer(text):
        path, first, last = m.group(1).rstrip("."), m.group(2), m.group(3)
        in_span = any(s <= m.start(1) < s + len(c) for s, c in spans)
        if (first is None and not in_span) or re.search(r"[<>*{}]", path) or path.startswith(NOT_HERE):
            continue
        ref = path + (f":{first}" if first else "") + (f"-{last}" if last else "")
        out.append((line(m.start(1)), ref, check_path(path, first, last)))
    for start, content in spans:
        for m in CLASS_ATTR.finditer(content):
            out.append((line(start + m.start(1)), m.group(1), check_class_attr(m.group(1))))
        for m in MODULE.finditer(content):
            ref = m.group(0)
            out.append((line(start + m.start(1)), ref, check_module(m.group(1), m.group(2))))
    for m in LINK.finditer(text):
        out.append((line(m.start(1)), m.group(1), check_link(page, m.group(1))))
    return out


def test_every_code_reference_of_the_pages_resolves():
    checked, broken = 0, []
    for page in PAGES:
        for lineno, ref, why in references(page):
            if why == "skip":
                continue
            checked += 1
            if why is not None:
                broken.append(f"{page.relative_to(ROOT)}:{lineno}: `{ref}`: {why}")
    print(f"{checked} references checked in {len(PAGES)} pages")
    assert checked > 100, f"only {checked} references found: has the pattern stopped matching the pages?"
    assert not broken, "references that do not resolve:\n" + "\n".join(broken)


def test_the_checks_refuse_what_does_not_resolve():
    # Each kind of reference, one that resolves and one that does not (a name, a line past the end, an anchor).
    assert check_class_attr("ReFPO.policy_loss") is None
    assert check_class_attr("ReFPO.reflow_coef") is None  # an option field in the class body
    assert check_class_attr("FlowGRPO.construct_algorithm") is None  # rsl_rl's PPO, through the bases
    assert "no attribute 'Options'" in check_class_attr("ReFPO.Options")
    assert "no class 'NoSuchClass'" in check_class_attr("NoSuchClass.x")
    assert check_module("refpo_warp.algorithms", "ReFPO") is None
    assert check_module("refpo_warp.algorithms.ReFPO", None) is None  # a package's import, followed
    assert check_module("refpo_warp.runner.runner.Runner", None) is None
    assert "defines or imports no" in check_module("refpo_warp.algorithms", "NoSuchAlgo")
    n = len((ROOT / "refpo_warp/algorithms/refpo.py").read_text(encoding="utf-8").splitlines())
    assert check_path("refpo_warp/algorithms/refpo.py", str(n), None) is None
    assert "has" in check_path("refpo_warp/algorithms/refpo.py", "1", str(n + 1))
    assert "no such file" in check_path("refpo_warp/no_such.py", None, None)
    assert check_link(ROOT / "docs/cli.md", "architecture.md#layers") is None
    assert "anchor" in check_link(ROOT / "docs/cli.md", "architecture.md#no-such-heading")


def test_the_command_table_of_docs_cli_is_the_command_list():
    # docs/cli.md's table is the docs' one list of the subcommands; `refpo --help` prints refpo_warp/cli/main.py's.
    from refpo_warp.cli.main import COMMANDS

    text = (ROOT / "docs/cli.md").read_text(encoding="utf-8")
    table = text[text.index("## The `refpo` command") : text.index("All of them read one grammar")]
    listed = re.findall(r"^\| `refpo ([\w-]+)` \|", table, re.MULTILINE)
    assert listed == list(COMMANDS), f"docs/cli.md lists {listed}; refpo --help lists {list(COMMANDS)}"
