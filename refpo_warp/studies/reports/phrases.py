"""Words the results pages put around their numbers, shared by the page scripts under docs/results/."""

from collections.abc import Iterable


def and_list(items: Iterable[str]) -> str:
    """``items`` as an English list: '', 'a', 'a and b', 'a, b and c' (no comma before the last)."""
    listed = list(items)
    if len(listed) <= 1:
        return "".join(listed)
    return ", ".join(listed[:-1]) + " and " + listed[-1]
