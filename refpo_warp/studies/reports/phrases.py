"""Words the results pages put around their numbers, shared by the page scripts under docs/results/."""

from collections.abc import Iterable, Mapping


def and_list(items: Iterable[str]) -> str:
    """``items`` as an English list: '', 'a', 'a and b', 'a, b and c' (no comma before the last)."""
    listed = list(items)
    if len(listed) <= 1:
        return "".join(listed)
    return ", ".join(listed[:-1]) + " and " + listed[-1]


def value_range(values: Iterable[float], fmt: str, sep: str = "-") -> str:
    """The smallest and the largest of ``values`` formatted with ``fmt`` ('.2f'), joined by ``sep``; one value where
    the two read the same."""
    listed = list(values)
    lo, hi = format(min(listed), fmt), format(max(listed), fmt)
    return lo if lo == hi else f"{lo}{sep}{hi}"


def machine_text(machine: Mapping | None, unrecorded: str) -> str:
    """Where a run trained, from its ``eval.json`` record (``refpo_warp/utils/machine.py``): cores, CPU, its widest
    vector instructions and torch threads; ``unrecorded`` for a run made before runs recorded it."""
    if machine is None:
        return unrecorded
    threads = machine["torch_threads"]
    return (
        f"a {machine['cpu_count']}-core {machine['cpu']} ({machine['cpu_capability']}), "
        + ("one torch thread" if threads == 1 else f"{threads} torch threads")
        + " a run"
    )
