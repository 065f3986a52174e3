#!/usr/bin/env python
"""This folder's README.md, from README.template.md and the investigation scripts beside it:

    python docs/results/humanoid/make_page.py [--check]

Each script's row comes from its own docstring: its first sentence up to the parenthesis (what it measures), the
``docs/humanoid.md`` section it names in that parenthesis (checked to be a heading of that page), and the command in
double backquotes on its next line. A script without that docstring, or one naming a section the page does not have,
is an error.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from refpo_warp.studies.reports.results_page import page_main

HERE = Path(__file__).resolve().parent
DOC = HERE.parents[2] / "docs" / "humanoid.md"
# 'What it measures (docs/humanoid.md, "Section"):' then '``python ... [options]``.'
FIRST = re.compile(
    r'\A(?P<what>[^(]+?) \(docs/humanoid\.md, "(?P<section>[^"]+)"\):\s*``(?P<command>[^`]+)``', re.DOTALL
)


def rows() -> str:
    headings = [
        line.lstrip("#").strip() for line in DOC.read_text(encoding="utf-8").splitlines() if line.startswith("#")
    ]
    out = ["| script | what it measures | its numbers | command |", "|---|---|---|---|"]
    for path in sorted(HERE.glob("*.py")):
        if path.name == Path(__file__).name:
            continue
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        match = FIRST.match(doc)
        if match is None:
            raise SystemExit(f"{path}: its docstring must start 'What (docs/humanoid.md, \"Section\"): ``command``'")
        section = match["section"]
        if not any(h == section or h.startswith(section + " (") for h in headings):
            raise SystemExit(f"{path}: {DOC.name} has no section '{section}'")
        out.append(
            f'| `{path.name}` | {match["what"].strip()} | `docs/humanoid.md`, "{section}" | '
            f"`{' '.join(match['command'].split())}` |"
        )
    return "\n".join(out)


def main() -> None:
    page_main(__doc__.split("\n\n")[0], HERE / "README.template.md", lambda: {"scripts_table": rows()})


if __name__ == "__main__":
    main()
