"""Words the results pages put around their numbers, shared by the page scripts under docs/results/."""

from collections.abc import Iterable


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
