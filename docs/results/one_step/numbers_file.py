"""The analysis' numbers written as JSON (one_step.json, screen.json), floats rounded to what the page and figures
read."""

import json
from pathlib import Path


def rounded(value, digits: int = 4):
    """``value`` with every float rounded to ``digits`` significant digits (the JSON behind the figures, kept small)."""
    if isinstance(value, float):
        return float(f"{value:.{digits}g}")
    if isinstance(value, dict):
        return {key: rounded(item, digits) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [rounded(item, digits) for item in value]
    return value


def write_numbers(numbers: dict, path: Path) -> None:
    """The numbers behind the figures, rounded and compact (the point_mass paths are most of them)."""
    from refpo_warp.utils.atomic_files import write_text

    write_text(path, json.dumps(rounded(numbers), separators=(",", ":")))
