"""A results page written whole by its script: a Markdown template with ``{{ name }}`` fields, and the values the
script computes from committed data files. The template's prose types no number of its own: outside its fields,
code spans, fenced blocks, link targets and comments, a digit may appear only inside a phrase its header allows
(``N = 10``, ``95 %``: names, not measurements). ``tests/docs/test_results_pages.py`` rebuilds every page and
checks every template.

A template begins with its header, a YAML comment::

    <!-- page
    script: make_page.py              # the script (in the template's folder) that writes the page, with its flags
    allow: ["N = 1", "N = 10"]        # phrases with digits the prose may hold
    -->

``README.template.md`` writes ``README.md`` (the template's name less ``.template``). Every page at once:
``python -m refpo_warp.studies.reports.results_page [--check]`` (the pages under docs/results/).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml

from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

SUFFIX = ".template.md"
FIELD = re.compile(r"\{\{\s*([A-Za-z_][A-Za-z0-9_]*)\s*\}\}")
HEADER = re.compile(r"\A<!-- page\n(.*?)\n-->\n", re.DOTALL)
# What the prose check leaves out: fenced blocks, code spans, link and image targets, HTML comments.
NOT_PROSE = re.compile(r"```.*?```|`[^`\n]*`|\]\([^)\s]*\)|<!--.*?-->", re.DOTALL)


@dataclass(frozen=True)
class Template:
    path: Path
    script: str
    allow: tuple[str, ...]
    body: str

    @property
    def page(self) -> Path:
        return self.path.with_name(self.path.name[: -len(SUFFIX)] + ".md")

    @property
    def fields(self) -> list[str]:
        return list(dict.fromkeys(FIELD.findall(self.body)))


def load_template(path: str | Path) -> Template:
    path = Path(path)
    if not path.name.endswith(SUFFIX):
        raise ConfigError(f"{path}: a page template's name ends in {SUFFIX}")
    text = path.read_text(encoding="utf-8")
    match = HEADER.match(text)
    if match is None:
        raise ConfigError(f"{path}: a page template starts with its '<!-- page' header (script:, allow:)")
    header = yaml.safe_load(match.group(1)) or {}
    unknown = set(header) - {"script", "allow"}
    if unknown or "script" not in header:
        raise ConfigError(f"{path}: the header takes script: (required) and allow:, got {sorted(header)}")
    allow = tuple(str(a) for a in header.get("allow", []))
    return Template(path, str(header["script"]), allow, text[match.end() :])


def typed_numbers(template: Template) -> list[str]:
    """The lines of the template's prose that hold a digit of their own (each with the text around it)."""
    prose = NOT_PROSE.sub(" ", FIELD.sub(" ", template.body))
    for phrase in sorted(template.allow, key=len, reverse=True):
        prose = prose.replace(phrase, " ")
    return [line.strip() for line in prose.splitlines() if re.search(r"\d", line)]


def script_command(template: Template, check: bool = False) -> list[str]:
    """The command that writes (or, with ``check``, compares) the template's page."""
    import shlex
    import sys

    script, *flags = shlex.split(template.script)
    return [sys.executable, str(template.path.parent / script), *flags, *(["--check"] if check else [])]


def render(template: Template, values: Mapping[str, object]) -> str:
    """The page: the template's fields filled in. A field without a value, or a value no field uses, is an error:
    either is a page that says something other than its script computes."""
    missing = [f for f in template.fields if f not in values]
    unused = sorted(set(values) - set(template.fields))
    if missing or unused:
        raise ConfigError(f"{template.path}: fields without a value {missing}, values without a field {unused}")
    script = template.path.parent / template.script.split()[0]
    script = script.relative_to(REPO_ROOT) if script.is_relative_to(REPO_ROOT) else script
    banner = (
        f"<!-- Written by `python {script}` from {template.path.name} and the data files it reads: "
        "edit those, not this page. -->\n"
    )
    return banner + FIELD.sub(lambda m: str(values[m.group(1)]), template.body)


def write_page(template_path: str | Path, values: Mapping[str, object], check: bool = False) -> bool:
    """Write the template's page (atomically), or with ``check`` compare it with the page on disk and print the
    difference. Returns whether the page on disk was already what the data says."""
    template = load_template(template_path)
    text = render(template, values)
    old = template.page.read_text(encoding="utf-8") if template.page.exists() else ""
    if check:
        if old != text:
            diff = difflib.unified_diff(
                old.splitlines(), text.splitlines(), str(template.page), "from the data", lineterm="", n=1
            )
            print("\n".join(diff))
        return old == text
    if old != text:
        write_text(template.page, text)
    return old == text


def templates(root: str | Path) -> list[Template]:
    """Every page template under ``root``."""
    return [load_template(p) for p in sorted(Path(root).rglob("*" + SUFFIX))]


def main_args(description: str):
    """The command line every page script takes: ``--check`` compares instead of writing (the pages' test)."""
    import argparse

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--check", action="store_true", help="compare the page with what the data says; exit 1 if not")
    return parser


def page_main(
    description: str,
    template: Path,
    values: Callable[[], Mapping[str, object]],
    add_runs: Callable[[Path], None] | None = None,
) -> None:
    """A page script's command line: write its page from ``values()`` (``--check``: compare, exit 1 on a difference).
    With ``add_runs``, ``--add-runs DIR ...`` first adds each sweep dir's finished runs to the page's committed data."""
    import sys

    parser = main_args(description)
    if add_runs is not None:
        parser.add_argument("--add-runs", nargs="*", default=[], type=Path, help="sweep dirs whose new runs to add")
    args = parser.parse_args()
    if add_runs is not None:
        for sweep_dir in args.add_runs:
            add_runs(sweep_dir)
    same = write_page(template, values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


def main() -> None:
    import subprocess
    import sys

    parser = main_args("Write (or --check) every results page under docs/results/ with its own script.")
    args = parser.parse_args()
    failed = []
    for template in templates(REPO_ROOT / "docs" / "results"):
        done = subprocess.run(script_command(template, args.check), check=False, cwd=REPO_ROOT)
        state = ("same" if args.check else "written") if done.returncode == 0 else "CHANGED" if args.check else "FAILED"
        print(f"{state}: {template.page.relative_to(REPO_ROOT)}")
        failed += [] if done.returncode == 0 else [str(template.page)]
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
