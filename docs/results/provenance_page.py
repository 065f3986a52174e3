#!/usr/bin/env python
"""The page of where each committed result comes from (``provenance.md``), from ``provenance.yaml``:

    python docs/results/provenance_page.py [--check]

One row per entry: the results folder (linked to the page that gives its command), its runs (committed of those the
command makes), the command, and whether its runs' ``config.yaml`` match what the command resolves to on today's code
or, where not, the commit that added them and each key that differs (``refpo_warp/studies/reports/provenance.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import yaml

from refpo_warp.studies.reports.provenance import ABSENT, Checked, check_all
from refpo_warp.studies.reports.results_page import main_args, write_page

HERE = Path(__file__).resolve().parent


def shown(value: object) -> str:
    if value == ABSENT:
        return ABSENT
    return yaml.safe_dump(value, default_flow_style=True, width=10_000).removesuffix("\n...\n").strip()


def state(c: Checked) -> str:
    if not c.difference:
        return "matches today"
    commits = ", ".join(f"`{commit}`" for commit in c.entry.made_at) or "(not recorded)"
    keys = "; ".join(f"`{key}: {shown(saved)} → {shown(today)}`" for key, (saved, today) in c.difference.items())
    return f"made at {commits}: {keys}"


def row(c: Checked) -> str:
    folder = f"[{c.entry.folder}]({c.entry.page})" if c.entry.page else f"`{c.entry.folder}`"
    runs = str(len(c.committed)) if len(c.committed) == len(c.made) else f"{len(c.committed)} of {len(c.made)}"
    command = f"`{c.entry.command}`" + (f" (trials: `{c.entry.trials}`)" if c.entry.trials else "")
    return f"| {folder} | {runs} | {command} | {state(c)} |"


def values() -> dict[str, object]:
    checked = check_all()
    drifted = [c for c in checked if c.difference]
    runs = sum(len(c.committed) for c in checked)
    drifted_runs = sum(len(c.committed) for c in drifted)
    return {
        "runs": runs,
        "entries": len(checked),
        "matching": runs - drifted_runs,
        "drifted": drifted_runs,
        "drifted_entries": len(drifted),
        "table": "\n".join(["| folder | runs | command | state |", "|---|---|---|---|", *map(row, checked)]),
    }


def main() -> None:
    args = main_args(__doc__.splitlines()[0]).parse_args()
    same = write_page(HERE / "provenance.template.md", values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


if __name__ == "__main__":
    main()
