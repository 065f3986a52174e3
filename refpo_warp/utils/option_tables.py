"""Option tables as Markdown, made from a class's option fields (``refpo_warp/utils/options.py``): the rows the docs'
tables are made of (``refpo_warp/config/option_docs.py`` fills the pages; a family's own tables, e.g.
``tasks/dmc/doc_tables.py``, use the same rows)."""

from __future__ import annotations

from typing import Any

from refpo_warp.utils.option_field import SECTION
from refpo_warp.utils.options import declared_options, option_fields


def shown_value(value: Any) -> str:
    """A default as a config file writes it."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(shown_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {shown_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, float):
        short = f"{value:g}"
        return short if "e" in short else repr(value)
    return f"`{value}`" if isinstance(value, str) else str(value)


def option_cells(cls: type) -> list[list[str]]:
    """(option, default, valid values, meaning) of each option ``cls`` declares itself (not its bases'; a section is
    no option: it has a table of its own)."""
    declared = declared_options(cls)
    rows = []
    for name, f in option_fields(cls).items():
        if SECTION in f.metadata:
            continue
        found = declared[name]
        rule = found.rule
        valid = ("null or " if rule.optional else "") + rule.describe() if rule is not None else "any value"
        rows.append([f"`{name}`", shown_value(found.default), valid, found.doc])
    return rows


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table (a ``|`` in a cell escaped)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |" for cells in rows]
    return "\n".join(lines) + "\n"
