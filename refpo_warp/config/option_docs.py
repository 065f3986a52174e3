"""The option tables of the docs, made from the classes' option fields (default, valid values, meaning), so a page
cannot state another default than the code. A table stands in a page between two markers naming the class::

    <!-- options refpo_warp.algorithms:ReFPO -->
    | option | default | valid values | meaning |
    ...
    <!-- end options -->

A table that is not one class's options (e.g. docs/dmc.md's tasks and their rewards) stands between markers naming
the function, ``module:function`` returning the Markdown, that makes it::

    <!-- table refpo_warp.tasks.dmc.doc_tables:tasks_table -->
    ...
    <!-- end table -->

``python -m refpo_warp.config.option_docs docs/algorithms.md`` rewrites every table of a page;
``tests/docs/test_option_tables.py`` fails when a page's table is not the one its class or function makes.
"""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

from refpo_warp.config.classes import resolve_class
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.option_tables import markdown_table, option_cells

BLOCK = re.compile(r"(<!-- options (?P<name>\S+) -->\n)(?P<table>.*?)(<!-- end options -->)", re.DOTALL)
MADE = re.compile(r"(<!-- table (?P<name>\S+) -->\n)(?P<table>.*?)(<!-- end table -->)", re.DOTALL)


def options_table(class_name: str) -> str:
    """The Markdown table of the options ``class_name`` declares itself (not its bases')."""
    return markdown_table(["option", "default", "valid values", "meaning"], option_cells(resolve_class(class_name)))


def made_table(function_name: str) -> str:
    """The Markdown table that the function ``module:function`` returns."""
    module, _, name = function_name.partition(":")
    return getattr(importlib.import_module(module), name)()


def with_tables(text: str) -> str:
    """``text`` with every marked table made again from its class or function."""
    text = BLOCK.sub(lambda m: m.group(1) + options_table(m.group("name")) + m.group(4), text)
    return MADE.sub(lambda m: m.group(1) + made_table(m.group("name")) + m.group(4), text)


def main(argv: list[str]) -> int:
    for path in map(Path, argv):
        text = path.read_text(encoding="utf-8")
        new = with_tables(text)
        if new != text:
            write_text(path, new)
            print(f"rewrote the option tables of {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
